// RDF/XML (OWL files as Protégé and SkiROS2 write them) through Raptor, the Redland
// parser: no hand-written XML or RDF parsing. Nothing outside the text is read: no
// network, no files, no external entities (an ontology's owl:imports are resolved by the
// loader, from files the user names).
#include <raptor2.h>

#include <cstring>
#include <memory>

#include "skillbus/wm/model.hpp"
#include "skillbus/wm/rdf.hpp"

namespace skillbus::wm {

namespace {

struct XmlReadState {
  Prefixes* prefixes;
  std::vector<Triple>* out;
  std::string error;
};

std::string uri_text(raptor_uri* u) { return u ? reinterpret_cast<const char*>(raptor_uri_as_string(u)) : ""; }

Term to_term(const raptor_term* t) {
  Term out;
  switch (t->type) {
    case RAPTOR_TERM_TYPE_URI:
      out.value = uri_text(t->value.uri);
      break;
    case RAPTOR_TERM_TYPE_BLANK:
      out.kind = Term::Blank;
      out.value.assign(reinterpret_cast<const char*>(t->value.blank.string), t->value.blank.string_len);
      break;
    case RAPTOR_TERM_TYPE_LITERAL:
      out.kind = Term::Literal;
      out.value.assign(reinterpret_cast<const char*>(t->value.literal.string), t->value.literal.string_len);
      out.datatype = uri_text(t->value.literal.datatype);
      if (t->value.literal.language)
        out.lang.assign(reinterpret_cast<const char*>(t->value.literal.language), t->value.literal.language_len);
      break;
    default:
      throw WmError("an RDF term of unknown kind");
  }
  return out;
}

void on_statement(void* user, raptor_statement* s) {
  auto* st = static_cast<XmlReadState*>(user);
  if (!st->error.empty()) return;
  try {
    st->out->push_back(Triple{to_term(s->subject), to_term(s->predicate), to_term(s->object)});
  } catch (const WmError& e) {
    st->error = e.what();
  }
}

void on_namespace(void* user, raptor_namespace* ns) {
  auto* st = static_cast<XmlReadState*>(user);
  const unsigned char* prefix = raptor_namespace_get_prefix(ns);
  raptor_uri* uri = raptor_namespace_get_uri(ns);
  // (the default namespace has no prefix; a prefix already known keeps its namespace, so
  // a file cannot rename "skiros" under the world's feet)
  if (!prefix || !uri || st->prefixes->all().count(reinterpret_cast<const char*>(prefix))) return;
  st->prefixes->add(reinterpret_cast<const char*>(prefix), uri_text(uri));
}

void on_log(void* user, raptor_log_message* m) {
  auto* st = static_cast<XmlReadState*>(user);
  if (m->level < RAPTOR_LOG_LEVEL_ERROR || !st->error.empty()) return;
  std::string where;
  if (m->locator && m->locator->line > 0) where = "line " + std::to_string(m->locator->line) + ": ";
  st->error = where + (m->text ? m->text : "malformed RDF/XML");
}

}  // namespace

std::vector<Triple> parse_rdf_xml(const std::string& text, Prefixes& prefixes, const std::string& source,
                                  const std::string& base_iri) {
  std::vector<Triple> out;
  XmlReadState st{&prefixes, &out, ""};
  std::unique_ptr<raptor_world, void (*)(raptor_world*)> world(raptor_new_world(), raptor_free_world);
  if (!world || raptor_world_open(world.get())) throw WmError(source + ": cannot start the RDF/XML parser");
  raptor_world_set_log_handler(world.get(), &st, on_log);
  std::unique_ptr<raptor_parser, void (*)(raptor_parser*)> parser(raptor_new_parser(world.get(), "rdfxml"),
                                                                   raptor_free_parser);
  if (!parser) throw WmError(source + ": no RDF/XML parser in this Raptor");
  raptor_parser_set_option(parser.get(), RAPTOR_OPTION_NO_NET, nullptr, 1);
  raptor_parser_set_option(parser.get(), RAPTOR_OPTION_NO_FILE, nullptr, 1);
  raptor_parser_set_option(parser.get(), RAPTOR_OPTION_LOAD_EXTERNAL_ENTITIES, nullptr, 0);
  raptor_parser_set_statement_handler(parser.get(), &st, on_statement);
  raptor_parser_set_namespace_handler(parser.get(), &st, on_namespace);
  std::unique_ptr<raptor_uri, void (*)(raptor_uri*)> base(
      raptor_new_uri(world.get(), reinterpret_cast<const unsigned char*>(base_iri.c_str())), raptor_free_uri);
  if (!base) throw WmError(source + ": bad base IRI " + base_iri);
  int rc = raptor_parser_parse_start(parser.get(), base.get());
  if (rc == 0)
    rc = raptor_parser_parse_chunk(parser.get(), reinterpret_cast<const unsigned char*>(text.data()), text.size(), 1);
  if (!st.error.empty()) throw WmError(source + ": " + st.error);
  if (rc != 0) throw WmError(source + ": malformed RDF/XML");
  return out;
}

bool looks_like_rdf_xml(const std::string& text) {
  const size_t start = text.find_first_not_of(" \t\r\n\xEF\xBB\xBF");  // (and a UTF-8 byte order mark)
  if (start == std::string::npos) return false;
  for (const char* opening : {"<?xml", "<!DOCTYPE", "<rdf:RDF", "<!--"})
    if (text.compare(start, std::strlen(opening), opening) == 0) return true;
  return false;
}

std::vector<Triple> parse_rdf(const std::string& text, Prefixes& prefixes, const std::string& source,
                              const std::string& base_iri) {
  return looks_like_rdf_xml(text) ? parse_rdf_xml(text, prefixes, source, base_iri)
                                  : parse_turtle(text, prefixes, source);
}

}  // namespace skillbus::wm
