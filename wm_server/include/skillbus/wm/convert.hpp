// Between the world model's types and their LCM messages (lcmtypes/wm_*.lcm).
#pragma once

#include "skillbus/wm/model.hpp"
#include "skillbus_msgs/wm_element_t.hpp"
#include "skillbus_msgs/wm_op_t.hpp"
#include "skillbus_msgs/wm_relation_t.hpp"

namespace skillbus::wm {

// Throws WmError on a value of unknown type.
Element from_msg(const skillbus_msgs::wm_element_t& m);
skillbus_msgs::wm_element_t to_msg(const Element& e);
Relation from_msg(const skillbus_msgs::wm_relation_t& m);
skillbus_msgs::wm_relation_t to_msg(const Relation& r);
Op from_msg(const skillbus_msgs::wm_op_t& m);
skillbus_msgs::wm_op_t to_msg(const Op& op);
std::map<std::string, std::vector<Value>> properties_from_msg(const std::vector<skillbus_msgs::wm_property_t>& props,
                                                              const std::string& owner);

}  // namespace skillbus::wm
