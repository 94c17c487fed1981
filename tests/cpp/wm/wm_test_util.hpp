#pragma once

#include <fstream>
#include <iterator>
#include <string>

#include "skillbus/wm/ontology.hpp"
#include "skillbus/wm/store.hpp"

namespace skillbus::wm::test {

inline std::string read(const std::string& path) {
  std::ifstream f(path);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

// The shipped ontology (wm_server/ontology/skiros.ttl).
inline Ontology& ontology() {
  static Ontology o = [] {
    Ontology x;
    Prefixes p;
    x.load_turtle(read(SKILLBUS_TEST_ONTOLOGY), p, "skiros.ttl");
    return x;
  }();
  return o;
}

inline Element element(const std::string& id, const std::string& type, const std::string& label = "",
                       std::map<std::string, std::vector<Value>> props = {}) {
  return Element{id, type, label, std::move(props)};
}

inline Op add(Element e) { return Op{Op::AddElement, std::move(e), {}}; }
inline Op relate(const std::string& s, const std::string& p, const std::string& o) {
  return Op{Op::AddRelation, {}, Relation{s, p, o}};
}

}  // namespace skillbus::wm::test
