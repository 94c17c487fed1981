// Turtle in and out, on serd, and RDF/XML in, on Raptor (no hand-written RDF parsing). Terms keep full IRIs;
// Prefixes compacts them to "prefix:local" for the world model and expands them back.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace skillbus::wm {

struct Term {
  enum Kind { Iri, Blank, Literal };
  Kind kind = Iri;
  std::string value;     // IRI, blank node id, or literal text
  std::string datatype;  // literal: full datatype IRI, "" if none
  std::string lang;
};

struct Triple {
  Term s, p, o;
};

class Prefixes {
 public:
  Prefixes();  // rdf, rdfs, owl, xsd and skiros are always known
  void add(const std::string& prefix, const std::string& ns);
  std::string compact(const std::string& iri) const;   // the IRI itself if no prefix fits
  std::string expand(const std::string& curie) const;  // the text itself if no prefix fits
  const std::map<std::string, std::string>& all() const { return by_prefix_; }

 private:
  std::map<std::string, std::string> by_prefix_;
};

extern const char* const kRdfType;
extern const char* const kRdfsLabel;
extern const char* const kRdfsSubClassOf;
extern const char* const kRdfsSubPropertyOf;
extern const char* const kRdfsRange;
extern const char* const kOwlNamedIndividual;
extern const char* const kOwlClass;
extern const char* const kXsd;

// Parses Turtle; prefixes it declares are added to `prefixes`. Throws WmError with
// serd's message (line and column) on malformed input.
std::vector<Triple> parse_turtle(const std::string& text, Prefixes& prefixes, const std::string& source = "input");

// Parses RDF/XML with Raptor (no network, no files, no external entities); namespaces
// with a prefix it declares are added to `prefixes` (a prefix already known keeps its
// namespace). Relative IRIs resolve against `base_iri`.
std::vector<Triple> parse_rdf_xml(const std::string& text, Prefixes& prefixes, const std::string& source,
                                  const std::string& base_iri);
// RDF/XML when the text starts like XML (<?xml, <!DOCTYPE, <rdf:RDF, <!--), else Turtle.
bool looks_like_rdf_xml(const std::string& text);
std::vector<Triple> parse_rdf(const std::string& text, Prefixes& prefixes, const std::string& source,
                              const std::string& base_iri);

// Appends `more` to `into`, a blank node of `more` whose label `into` already has renamed
// (consistently, to a label neither has): each reader names its blank nodes from b1 on, so
// the triples of two files written as one document would make one node of two (two
// restrictions into one). Labels that do not clash are kept.
void append_apart(std::vector<Triple>& into, const std::vector<Triple>& more);

// Writes triples as Turtle with the given prefixes, subjects grouped in input order.
std::string write_turtle(const std::vector<Triple>& triples, const Prefixes& prefixes);

}  // namespace skillbus::wm
