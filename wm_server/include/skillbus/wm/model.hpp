// The world model's data: elements (individuals of ontology concepts) with typed
// properties, and relations between them. Ids, types, predicates and property keys are
// compact IRIs ("skiros:Cube-3", "skiros:contain").
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <variant>
#include <vector>

namespace skillbus::wm {

using Value = std::variant<std::string, int64_t, double, bool>;  // STRING, INT, FLOAT, BOOL

const char* value_type_name(const Value& v);  // "string", "int", "float", "bool"

struct Element {
  std::string id, type, label;
  std::map<std::string, std::vector<Value>> properties;
  bool operator==(const Element& o) const {
    return id == o.id && type == o.type && label == o.label && properties == o.properties;
  }
};

struct Relation {
  std::string subject, predicate, object;
  bool operator<(const Relation& o) const {
    return std::tie(subject, predicate, object) < std::tie(o.subject, o.predicate, o.object);
  }
  bool operator==(const Relation& o) const {
    return subject == o.subject && predicate == o.predicate && object == o.object;
  }
};

struct Op {
  // ExpectElement changes nothing: the transaction fails unless the element is exactly as
  // given (type, label, properties). An editor sends the element as it read it before its
  // change, so an edit of an element that changed meanwhile is refused, not lost.
  enum Kind {
    AddElement = 0, UpdateElement = 1, RemoveElement = 2, AddRelation = 3, RemoveRelation = 4, ExpectElement = 5
  };
  Kind kind;
  Element element;
  Relation relation;
};

// A request that cannot be applied; the message names what was wrong.
class WmError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace skillbus::wm
