#include "skillbus/wm/rdf.hpp"

#include <serd/serd.h>

#include <cctype>
#include <cstdarg>
#include <cstdio>
#include <map>
#include <regex>
#include <set>
#include <string>

#include "skillbus/wm/model.hpp"

namespace skillbus::wm {

const char* const kRdfType = "http://www.w3.org/1999/02/22-rdf-syntax-ns#type";
const char* const kRdfsLabel = "http://www.w3.org/2000/01/rdf-schema#label";
const char* const kRdfsSubClassOf = "http://www.w3.org/2000/01/rdf-schema#subClassOf";
const char* const kRdfsSubPropertyOf = "http://www.w3.org/2000/01/rdf-schema#subPropertyOf";
const char* const kRdfsRange = "http://www.w3.org/2000/01/rdf-schema#range";
const char* const kOwlNamedIndividual = "http://www.w3.org/2002/07/owl#NamedIndividual";
const char* const kOwlClass = "http://www.w3.org/2002/07/owl#Class";
const char* const kXsd = "http://www.w3.org/2001/XMLSchema#";

Prefixes::Prefixes() {
  add("rdf", "http://www.w3.org/1999/02/22-rdf-syntax-ns#");
  add("rdfs", "http://www.w3.org/2000/01/rdf-schema#");
  add("owl", "http://www.w3.org/2002/07/owl#");
  add("xsd", kXsd);
  add("skiros", "http://rvmi.aau.dk/ontologies/skiros.owl#");
}

void Prefixes::add(const std::string& prefix, const std::string& ns) { by_prefix_[prefix] = ns; }

std::string Prefixes::compact(const std::string& iri) const {
  const std::pair<const std::string, std::string>* best = nullptr;
  for (const auto& kv : by_prefix_)
    if (iri.compare(0, kv.second.size(), kv.second) == 0 && (!best || kv.second.size() > best->second.size()))
      best = &kv;
  return best ? best->first + ":" + iri.substr(best->second.size()) : iri;
}

std::string Prefixes::expand(const std::string& curie) const {
  const auto colon = curie.find(':');
  if (colon == std::string::npos) return curie;
  auto it = by_prefix_.find(curie.substr(0, colon));
  return it == by_prefix_.end() ? curie : it->second + curie.substr(colon + 1);
}

namespace {

struct ReadState {
  SerdEnv* env;
  Prefixes* prefixes;
  std::vector<Triple>* out;
  std::string error;
};

std::string node_text(const SerdNode* n) { return std::string(reinterpret_cast<const char*>(n->buf), n->n_bytes); }

Term to_term(ReadState& st, const SerdNode* n, const SerdNode* datatype = nullptr, const SerdNode* lang = nullptr) {
  Term t;
  switch (n->type) {
    case SERD_BLANK:
      t.kind = Term::Blank;
      t.value = node_text(n);
      return t;
    case SERD_LITERAL:
      t.kind = Term::Literal;
      t.value = node_text(n);
      if (datatype && datatype->buf) t.datatype = to_term(st, datatype).value;
      if (lang && lang->buf) t.lang = node_text(lang);
      return t;
    case SERD_CURIE: {
      SerdNode full = serd_env_expand_node(st.env, n);
      if (!full.buf) throw WmError("undefined prefix in '" + node_text(n) + "'");
      t.value = node_text(&full);
      serd_node_free(&full);
      return t;
    }
    default:
      t.value = node_text(n);
      return t;
  }
}

SerdStatus on_prefix(void* handle, const SerdNode* name, const SerdNode* uri) {
  auto* st = static_cast<ReadState*>(handle);
  st->prefixes->add(node_text(name), node_text(uri));
  return serd_env_set_prefix(st->env, name, uri);
}

SerdStatus on_statement(void* handle, SerdStatementFlags, const SerdNode*, const SerdNode* s, const SerdNode* p,
                        const SerdNode* o, const SerdNode* dt, const SerdNode* lang) {
  auto* st = static_cast<ReadState*>(handle);
  try {
    st->out->push_back(Triple{to_term(*st, s), to_term(*st, p), to_term(*st, o, dt, lang)});
  } catch (const WmError& e) {
    st->error = e.what();
    return SERD_ERR_BAD_CURIE;
  }
  return SERD_SUCCESS;
}

SerdStatus on_error(void* handle, const SerdError* e) {
  auto* st = static_cast<ReadState*>(handle);
  char msg[512];
  va_list args;
  va_copy(args, *e->args);
  std::vsnprintf(msg, sizeof msg, e->fmt, args);
  va_end(args);
  std::string text = msg;
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  if (st->error.empty())
    st->error = "line " + std::to_string(e->line) + ", column " + std::to_string(e->col) + ": " + text;
  return SERD_SUCCESS;
}

}  // namespace

std::vector<Triple> parse_turtle(const std::string& text, Prefixes& prefixes, const std::string& source) {
  std::vector<Triple> out;
  ReadState st{serd_env_new(nullptr), &prefixes, &out, ""};
  for (const auto& [p, ns] : prefixes.all())
    serd_env_set_prefix_from_strings(st.env, reinterpret_cast<const uint8_t*>(p.c_str()),
                                     reinterpret_cast<const uint8_t*>(ns.c_str()));
  SerdReader* reader = serd_reader_new(SERD_TURTLE, &st, nullptr, nullptr, on_prefix, on_statement, nullptr);
  serd_reader_set_strict(reader, true);
  serd_reader_set_error_sink(reader, on_error, &st);
  const SerdStatus status = serd_reader_read_string(reader, reinterpret_cast<const uint8_t*>(text.c_str()));
  serd_reader_free(reader);
  serd_env_free(st.env);
  if (status != SERD_SUCCESS || !st.error.empty())
    throw WmError("malformed Turtle in " + source + ": " +
                  (st.error.empty() ? std::string(reinterpret_cast<const char*>(serd_strerror(status))) : st.error));
  return out;
}

namespace {

SerdNode uri_node(const std::string& s) { return serd_node_from_string(SERD_URI, reinterpret_cast<const uint8_t*>(s.c_str())); }

SerdNode term_node(const Term& t) {
  const auto* b = reinterpret_cast<const uint8_t*>(t.value.c_str());
  switch (t.kind) {
    case Term::Blank: return serd_node_from_string(SERD_BLANK, b);
    case Term::Literal: return serd_node_from_string(SERD_LITERAL, b);
    default: return serd_node_from_string(SERD_URI, b);
  }
}

// The prefixed name of an IRI ("skiros:Cube-2") when its local part is a plain Turtle
// local name, else "". serd writes an IRI as a prefixed name only when its local part is
// letters and digits, so ids such as Cube-2 would come out as full <...#Cube-2>.
std::string prefixed_name(const std::string& iri, const Prefixes& prefixes) {
  const std::string c = prefixes.compact(iri);
  if (c == iri) return "";
  const std::string local = c.substr(c.find(':') + 1);
  bool ok = !local.empty() && local[0] != '-';
  for (char ch : local) ok = ok && (std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '-');
  return ok ? c : "";
}

// A subject or object: an IRI as a prefixed name where one fits (predicates stay IRIs:
// serd writes rdf:type as "a" and the others' local parts are plain names).
SerdNode resource_node(const Term& t, const Prefixes& prefixes, std::string& storage) {
  if (t.kind == Term::Iri) {
    storage = prefixed_name(t.value, prefixes);
    if (!storage.empty()) return serd_node_from_string(SERD_CURIE, reinterpret_cast<const uint8_t*>(storage.c_str()));
  }
  return term_node(t);
}

// serd writes a literal typed xsd:integer, xsd:decimal or xsd:boolean bare (42, 1.5, true)
// without looking at its text: "1 . <a> <b> <c>"^^xsd:integer would come out as Turtle with
// a triple more, "abc"^^xsd:integer as Turtle that does not read, "1.0"^^xsd:integer read
// back as a decimal. Such a literal keeps its quotes: its datatype goes to serd as a prefixed
// name, which serd does not abbreviate. (A text that is the datatype's own Turtle token is
// written bare, as before.)
bool written_bare_safely(const Term& o) {
  static const std::string xsd = kXsd;
  if (o.kind != Term::Literal || o.datatype.compare(0, xsd.size(), xsd) != 0) return true;
  const std::string type = o.datatype.substr(xsd.size());
  static const std::regex integer(R"([+-]?[0-9]+)"), decimal(R"([+-]?[0-9]*\.[0-9]+)");
  if (type == "integer") return std::regex_match(o.value, integer);
  if (type == "decimal") return std::regex_match(o.value, decimal);
  if (type == "boolean") return o.value == "true" || o.value == "false";
  return true;  // (serd abbreviates no other datatype)
}

}  // namespace

void append_apart(std::vector<Triple>& into, const std::vector<Triple>& more) {
  std::set<std::string> taken;
  for (const Triple& t : into)
    for (const Term* x : {&t.s, &t.o})
      if (x->kind == Term::Blank) taken.insert(x->value);
  std::set<std::string> own;  // (the labels of `more`: a new one must not be one of them either)
  for (const Triple& t : more)
    for (const Term* x : {&t.s, &t.o})
      if (x->kind == Term::Blank) own.insert(x->value);
  std::map<std::string, std::string> renamed;
  for (const std::string& label : own) {
    if (!taken.count(label)) continue;
    std::string fresh;
    for (int n = 2; fresh.empty() || taken.count(fresh) || own.count(fresh); ++n) fresh = label + "_" + std::to_string(n);
    taken.insert(fresh);
    renamed[label] = fresh;
  }
  into.reserve(into.size() + more.size());
  for (Triple t : more) {
    for (Term* x : {&t.s, &t.o}) {
      if (x->kind != Term::Blank) continue;
      auto it = renamed.find(x->value);
      if (it != renamed.end()) x->value = it->second;
    }
    into.push_back(std::move(t));
  }
}

std::string write_turtle(const std::vector<Triple>& triples, const Prefixes& prefixes) {
  SerdEnv* env = serd_env_new(nullptr);
  SerdChunk chunk{nullptr, 0};
  SerdWriter* w = serd_writer_new(SERD_TURTLE, static_cast<SerdStyle>(SERD_STYLE_ABBREVIATED | SERD_STYLE_CURIED), env,
                                  nullptr, serd_chunk_sink, &chunk);
  for (const auto& [p, ns] : prefixes.all()) {
    SerdNode name = serd_node_from_string(SERD_LITERAL, reinterpret_cast<const uint8_t*>(p.c_str()));
    SerdNode uri = uri_node(ns);
    serd_env_set_prefix(env, &name, &uri);
    serd_writer_set_prefix(w, &name, &uri);
  }
  const bool xsd_declared = prefixes.expand("xsd:integer") == std::string(kXsd) + "integer";
  for (const auto& t : triples) {
    std::string s_name, o_name;
    SerdNode s = resource_node(t.s, prefixes, s_name), p = term_node(t.p), o = resource_node(t.o, prefixes, o_name);
    const std::string quoted_type = written_bare_safely(t.o) || !xsd_declared
                                        ? ""
                                        : "xsd:" + t.o.datatype.substr(std::string(kXsd).size());
    SerdNode dt = t.o.datatype.empty() ? SERD_NODE_NULL
                  : quoted_type.empty()
                      ? uri_node(t.o.datatype)
                      : serd_node_from_string(SERD_CURIE, reinterpret_cast<const uint8_t*>(quoted_type.c_str()));
    SerdNode lang =
        t.o.lang.empty() ? SERD_NODE_NULL : serd_node_from_string(SERD_LITERAL, reinterpret_cast<const uint8_t*>(t.o.lang.c_str()));
    serd_writer_write_statement(w, 0, nullptr, &s, &p, &o, t.o.datatype.empty() ? nullptr : &dt,
                                t.o.lang.empty() ? nullptr : &lang);
  }
  serd_writer_finish(w);
  serd_writer_free(w);
  serd_env_free(env);
  uint8_t* buf = serd_chunk_sink_finish(&chunk);
  std::string out(reinterpret_cast<const char*>(buf));
  serd_free(buf);
  return out;
}

}  // namespace skillbus::wm
