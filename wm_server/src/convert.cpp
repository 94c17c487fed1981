#include "skillbus/wm/convert.hpp"

#include <cmath>

namespace skillbus::wm {

using skillbus_msgs::wm_value_t;

std::map<std::string, std::vector<Value>> properties_from_msg(const std::vector<skillbus_msgs::wm_property_t>& props,
                                                              const std::string& owner) {
  std::map<std::string, std::vector<Value>> out;
  for (const auto& p : props) {
    auto& values = out[p.key];
    for (const auto& v : p.values) {
      switch (v.type) {
        case wm_value_t::STRING: values.emplace_back(v.s); break;
        case wm_value_t::INT: values.emplace_back(static_cast<int64_t>(v.i)); break;
        case wm_value_t::FLOAT:
          // A NaN or an infinity is never a pose, a size or a weight; stored, it would reach
          // every replica and every skill that reads it.
          if (!std::isfinite(v.f))
            throw WmError("property " + p.key + " of " + owner + " is not a finite number (" + std::to_string(v.f) +
                          ")");
          values.emplace_back(v.f);
          break;
        case wm_value_t::BOOL: values.emplace_back(static_cast<bool>(v.b)); break;
        default:
          throw WmError("property " + p.key + " of " + owner + " has a value of unknown type " + std::to_string(v.type));
      }
    }
  }
  return out;
}

Element from_msg(const skillbus_msgs::wm_element_t& m) {
  Element e;
  e.id = m.id;
  e.type = m.type;
  e.label = m.label;
  e.properties = properties_from_msg(m.properties, m.id.empty() ? "a new element" : m.id);
  return e;
}

skillbus_msgs::wm_element_t to_msg(const Element& e) {
  skillbus_msgs::wm_element_t m{};
  m.id = e.id;
  m.type = e.type;
  m.label = e.label;
  m.properties.reserve(e.properties.size());
  for (const auto& [key, values] : e.properties) {
    skillbus_msgs::wm_property_t& p = m.properties.emplace_back();  // (built in place: no copies)
    p.key = key;
    p.values.reserve(values.size());
    for (const auto& v : values) {
      wm_value_t& x = p.values.emplace_back();
      x.type = static_cast<int8_t>(v.index());
      if (auto s = std::get_if<std::string>(&v)) x.s = *s;
      if (auto i = std::get_if<int64_t>(&v)) x.i = *i;
      if (auto d = std::get_if<double>(&v)) x.f = *d;
      if (auto b = std::get_if<bool>(&v)) x.b = *b;
    }
    p.num_values = static_cast<int32_t>(p.values.size());
  }
  m.num_properties = static_cast<int32_t>(m.properties.size());
  return m;
}

Relation from_msg(const skillbus_msgs::wm_relation_t& m) { return Relation{m.subject, m.predicate, m.object}; }

skillbus_msgs::wm_relation_t to_msg(const Relation& r) {
  skillbus_msgs::wm_relation_t m{};
  m.subject = r.subject;
  m.predicate = r.predicate;
  m.object = r.object;
  return m;
}

Op from_msg(const skillbus_msgs::wm_op_t& m) {
  if (m.kind < 0 || m.kind > skillbus_msgs::wm_op_t::EXPECT_ELEMENT)
    throw WmError("unknown operation kind " + std::to_string(m.kind));
  return Op{static_cast<Op::Kind>(m.kind), from_msg(m.element), from_msg(m.relation)};
}

skillbus_msgs::wm_op_t to_msg(const Op& op) {
  skillbus_msgs::wm_op_t m{};
  m.kind = static_cast<int8_t>(op.kind);
  m.element = to_msg(op.element);
  m.relation = to_msg(op.relation);
  return m;
}

}  // namespace skillbus::wm
