#include "param_check.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>
#include <nlohmann/json.hpp>

#include "skillbus/wm/convert.hpp"

namespace skillbus::skills {

using skillbus_msgs::skill_param_t;
using skillbus_msgs::skill_value_t;

namespace {

const skill_param_t* declaration(const skillbus_msgs::skill_description_t& d, const std::string& key) {
  for (const auto& p : d.params)
    if (p.key == key) return &p;
  return nullptr;
}

std::string keys_of(const skillbus_msgs::skill_description_t& d) {
  std::string s;
  for (const auto& p : d.params) s += (s.empty() ? "" : ", ") + p.key;
  return s.empty() ? "none" : s;
}

const char* value_type_name(int8_t t) {
  switch (t) {
    case skill_value_t::STRING: return "str";
    case skill_value_t::INT: return "int";
    case skill_value_t::FLOAT: return "float";
    case skill_value_t::BOOL: return "bool";
    case skill_value_t::ELEMENT: return "element";
    case skill_value_t::JSON: return "list or dict";
  }
  return "unknown";
}

// The value type a data type travels as; -1 for a data type the manager does not know.
int expected_value_type(const std::string& data_type) {
  if (data_type == "float") return skill_value_t::FLOAT;
  if (data_type == "int") return skill_value_t::INT;
  if (data_type == "str") return skill_value_t::STRING;
  if (data_type == "bool") return skill_value_t::BOOL;
  if (data_type == "element") return skill_value_t::ELEMENT;
  if (data_type == "list" || data_type == "dict") return skill_value_t::JSON;
  return -1;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

}  // namespace

bool concrete_element(const skill_value_t& v) { return v.type == skill_value_t::ELEMENT && !v.element.id.empty(); }

std::string check_given(const skillbus_msgs::skill_description_t& d, const std::vector<Param>& given) {
  for (const auto& p : given) {
    const skill_param_t* decl = declaration(d, p.key);
    if (!decl) return d.type + " has no parameter " + p.key + " (it has: " + keys_of(d) + ")";
    if (p.data_type.empty()) continue;  // text from --start: typed by parse_text
    const int want = expected_value_type(decl->data_type);
    for (const auto& v : p.values) {
      const bool ok = v.type == want || (want == skill_value_t::FLOAT && v.type == skill_value_t::INT);
      if (!ok)
        return "parameter " + p.key + " of " + d.type + " is a " + decl->data_type + ", not a " + value_type_name(v.type);
      if (v.type == skill_value_t::FLOAT && !std::isfinite(v.f))  // (no skill process would take it)
        return "parameter " + p.key + " of " + d.type + ": " + std::to_string(v.f) + " is not a finite number";
      if (want == skill_value_t::JSON) {
        const auto j = nlohmann::json::parse(v.s, nullptr, false);
        if (j.is_discarded() || (decl->data_type == "list" && !j.is_array()) ||
            (decl->data_type == "dict" && !j.is_object()))
          return "parameter " + p.key + " of " + d.type + ": '" + v.s + "' is not a JSON " + decl->data_type;
      }
    }
  }
  return "";
}

std::string check_returned(const skillbus_msgs::skill_description_t& d, const std::vector<Param>& returned) {
  for (const auto& p : returned) {
    const skill_param_t* decl = declaration(d, p.key);
    if (!decl) return "a parameter " + p.key + " that " + d.type + " does not have (it has: " + keys_of(d) + ")";
    const int want = expected_value_type(decl->data_type);
    if (want < 0) continue;  // a data type the manager does not know travels as it came
    for (const auto& v : p.values) {
      if (v.type != want && !(want == skill_value_t::FLOAT && v.type == skill_value_t::INT))
        return "parameter " + p.key + " as a " + value_type_name(v.type) + ", where " + d.type + " declares a " +
               decl->data_type;
      if (v.type == skill_value_t::FLOAT && !std::isfinite(v.f))
        return "parameter " + p.key + " as " + std::to_string(v.f) + ", not a finite number";
    }
  }
  return "";
}

std::string fit_specified(const skillbus_msgs::skill_description_t& d, Param& p) {
  const skill_param_t* decl = declaration(d, p.key);
  if (!decl) return d.type + " has no parameter " + p.key;
  const bool one_json = p.values.size() == 1 && p.values[0].type == skill_value_t::JSON;
  if (decl->data_type == "list" && !one_json) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& v : p.values) {
      switch (v.type) {
        case skill_value_t::STRING: list.push_back(v.s); break;
        case skill_value_t::INT: list.push_back(v.i); break;
        case skill_value_t::FLOAT: list.push_back(v.f); break;
        case skill_value_t::BOOL: list.push_back(static_cast<bool>(v.b)); break;
        case skill_value_t::ELEMENT: list.push_back(v.element.id); break;
        default: list.push_back(nlohmann::json::parse(v.s, nullptr, false)); break;
      }
    }
    skill_value_t packed{};
    packed.type = skill_value_t::JSON;
    packed.s = list.dump();
    p.values = {packed};
    p.num_values = 1;
  }
  p.data_type = decl->data_type;
  p.concept = decl->concept;
  return check_given(d, {p});
}

std::string parse_text(const skillbus_msgs::skill_description_t& d, Param& p) {
  const skill_param_t* decl = declaration(d, p.key);
  if (!decl) return d.type + " has no parameter " + p.key + " (it has: " + keys_of(d) + ")";
  // Text is one text value (--start's KEY=VALUE): anything else given without a data type
  // would be read as its empty text, another value than the one sent.
  if (p.values.size() > 1 || (p.values.size() == 1 && p.values[0].type != skill_value_t::STRING))
    return "parameter " + p.key + ": a value without its data type must be one text value, not " +
           std::to_string(p.values.size()) + " value(s) of type " +
           value_type_name(p.values.empty() ? skill_value_t::STRING : p.values[0].type);
  const std::string text = p.values.empty() ? "" : p.values[0].s;
  const std::string what = "parameter " + p.key + ": '" + text + "' is ";
  skill_value_t v{};
  const std::string& t = decl->data_type;
  if (t == "element") {
    if (text.empty()) return "parameter " + p.key + ": an element id is needed (e.g. skiros:Cube-2)";
    v.type = skill_value_t::ELEMENT;
    v.element.id = text;
    v.element.type = decl->concept;
  } else if (t == "float" || t == "int") {
    size_t used = 0;
    try {
      if (t == "float") {
        v.type = skill_value_t::FLOAT;
        v.f = std::stod(text, &used);
      } else {
        v.type = skill_value_t::INT;
        v.i = std::stoll(text, &used);
      }
    } catch (const std::out_of_range&) {  // (a number beyond the type: 1e999, 2^70)
      return what + (t == "float" ? "not a finite float" : "beyond a 64-bit integer");
    } catch (const std::exception&) {
      used = 0;
    }
    if (text.empty() || used != text.size()) return what + "not a " + t;
    if (t == "float" && !std::isfinite(v.f)) return what + "not a finite float";
  } else if (t == "bool") {
    const std::string b = lower(text);
    v.type = skill_value_t::BOOL;
    if (b == "true" || b == "1")
      v.b = true;
    else if (b == "false" || b == "0")
      v.b = false;
    else
      return what + "not a bool (true, false, 1 or 0)";
  } else if (t == "list" || t == "dict") {
    const auto j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded() || (t == "list" && !j.is_array()) || (t == "dict" && !j.is_object()))
      return what + "not a JSON " + t;
    v.type = skill_value_t::JSON;
    v.s = j.dump();
  } else {
    v.type = skill_value_t::STRING;
    v.s = text;
  }
  p.data_type = t;
  p.concept = decl->concept;
  p.values = {v};
  p.num_values = 1;
  return "";
}

std::string check_elements(std::vector<Param>& params, const wm::WorldStore& world, const std::vector<std::string>& skip) {
  for (auto& p : params) {
    if (p.data_type != "element" || std::find(skip.begin(), skip.end(), p.key) != skip.end()) continue;
    for (auto& v : p.values) {
      if (!concrete_element(v)) continue;
      const std::string concept_name = p.concept.empty() ? v.element.type : p.concept;
      const wm::Element* e = world.get(v.element.id);
      if (!e) {
        std::string hint;  // a missing prefix is the usual slip: name the element meant
        for (const auto& [id, other] : world.elements()) {
          const auto colon = id.find(':');
          if (colon != std::string::npos && id.substr(colon + 1) == v.element.id) hint = " (did you mean " + id + "?)";
        }
        return "parameter " + p.key + ": no element " + v.element.id + " in the world model (expected a " +
               concept_name + ")" + hint;
      }
      if (!concept_name.empty() && !world.ontology().is_subclass(e->type, concept_name))
        return "parameter " + p.key + ": " + e->id + " is a " + e->type + ", not a " + concept_name;
      v.element = wm::to_msg(*e);
    }
  }
  return "";
}

}  // namespace skillbus::skills
