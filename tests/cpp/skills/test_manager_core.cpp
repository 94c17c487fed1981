// The skill manager's core without processes: the registry, the blackboard seen through
// scopes (remaps, specified values, a user's values) and the gathering of a node's
// parameters.
#include <gtest/gtest.h>

#include "blackboard.hpp"
#include "registry.hpp"
#include "skill_nodes.hpp"
#include "skill_params.hpp"

using namespace skillbus::skills;
using skillbus_msgs::skill_param_t;
using skillbus_msgs::skill_value_t;

namespace {

skillbus_msgs::skill_description_t description(const std::string& type, const std::string& label) {
  skillbus_msgs::skill_description_t d{};
  d.type = type;
  d.label = label;
  return d;
}

skillbus_msgs::skill_register_t announcement(const std::string& process, int64_t incarnation,
                                             std::vector<skillbus_msgs::skill_description_t> skills) {
  skillbus_msgs::skill_register_t r{};
  r.process = process;
  r.rpc_area = "SKPROC_" + process;
  r.incarnation = incarnation;
  r.skills = std::move(skills);
  r.num_skills = static_cast<int32_t>(r.skills.size());
  return r;
}

Param value(const std::string& key, int64_t i) {
  Param p{};
  p.key = key;
  p.data_type = "int";
  skill_value_t v{};
  v.type = skill_value_t::INT;
  v.i = i;
  p.values = {v};
  p.num_values = 1;
  return p;
}

Param decl(const std::string& key, int8_t kind, std::vector<int64_t> defaults = {}) {
  Param p = value(key, 0);
  p.values.clear();
  p.num_values = 0;
  p.param_type = kind;
  for (int64_t d : defaults) p.defaults.push_back(value(key, d).values[0]);
  p.num_defaults = static_cast<int32_t>(p.defaults.size());
  return p;
}

}  // namespace

TEST(Registry, AnnouncementsReplaceAProcessesSkillsAndLabelsAreUnique) {
  Registry r;
  EXPECT_TRUE(r.add(announcement("a", 1, {description("Pick", "pick"), description("Place", "place")})).empty());
  const auto refused = r.add(announcement("b", 7, {description("Pick", "pick"), description("Pick", "pick_fast")}));
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_EQ(refused[0], "skill pick of b: the label is served by a");
  EXPECT_EQ(r.find("Pick").size(), 2u);          // pick (a) and pick_fast (b), in label order
  EXPECT_EQ(r.find("Pick", "pick_fast").front().process, "b");
  r.add(announcement("a", 2, {description("Place", "place")}));  // a restarted, without Pick now
  EXPECT_EQ(r.find("Pick").size(), 1u);
  EXPECT_EQ(r.incarnation_of("a"), 2);
  EXPECT_EQ(r.processes(), (std::vector<std::string>{"a", "b"}));
}

TEST(Registry, ImplementationsOfATypeDeclareTheSameParameters) {
  // The manager checked a start's keys and values against the first implementation only
  // and Alternatives may run another: a key only the other declared was refused, one only
  // the first declared was taken and then ignored. A type has one set of parameters.
  auto with = [](skillbus_msgs::skill_description_t d, std::vector<Param> params) {
    d.params = std::move(params);
    d.num_params = static_cast<int32_t>(d.params.size());
    return d;
  };
  Registry r;
  const Param speed = decl("Speed", skill_param_t::OPTIONAL, {1});
  EXPECT_TRUE(r.add(announcement("a", 1, {with(description("Move", "move"), {speed})})).empty());
  Param speed_float = speed;
  speed_float.data_type = "float";
  Param speed_required = speed;
  speed_required.param_type = skill_param_t::REQUIRED;
  Param speed_default = speed;
  speed_default.defaults[0].i = 2;  // defaults and descriptions may differ
  speed_default.description = "how fast";
  const auto refused =
      r.add(announcement("b", 1,
                         {with(description("Move", "move_more"), {speed, decl("Force", skill_param_t::OPTIONAL)}),
                          with(description("Move", "move_less"), {}),
                          with(description("Move", "move_float"), {speed_float}),
                          with(description("Move", "move_required"), {speed_required}),
                          with(description("Move", "move_default"), {speed_default}),
                          with(description("Grip", "grip"), {speed_float})}));
  ASSERT_EQ(refused.size(), 4u);
  EXPECT_EQ(refused[0], "skill move_more of b: not the parameters of its type Move as skill move of a declares them: "
                        "it has parameter Force, which move has not");
  EXPECT_EQ(refused[1], "skill move_less of b: not the parameters of its type Move as skill move of a declares them: "
                        "it lacks parameter Speed of move");
  EXPECT_EQ(refused[2], "skill move_float of b: not the parameters of its type Move as skill move of a declares them: "
                        "its parameter Speed is a float, in move an int");
  EXPECT_EQ(refused[3], "skill move_required of b: not the parameters of its type Move as skill move of a declares "
                        "them: its parameter Speed is required, in move optional");
  EXPECT_EQ(r.find("Move").size(), 2u);  // move and move_default
  EXPECT_EQ(r.find("Grip").size(), 1u);  // another type: its own parameters
  // The only implementation of a type may change its parameters when its process restarts.
  EXPECT_TRUE(r.add(announcement("b", 2, {})).empty());
  EXPECT_TRUE(r.add(announcement("a", 2, {with(description("Move", "move"), {speed_float})})).empty());
}

TEST(Registry, WhatFindReturnsOutlivesTheNextAnnouncement) {
  // The manager pumps the bus inside a start request (it loads the world copy); an
  // announcement heard meanwhile replaced the entries that a started task still read
  // (a use after free, found by the fuzz run under AddressSanitizer).
  Registry r;
  r.add(announcement("a", 1, {description("Pick", "pick")}));
  const auto found = r.find("Pick");
  r.add(announcement("a", 2, {description("Place", "place")}));
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found.front().description.label, "pick");
  EXPECT_EQ(found.front().incarnation, 1);
  EXPECT_TRUE(r.find("Pick").empty());
}

TEST(Registry, ADroppedProcessIsNamedUntilItsTypeIsServedAgain) {
  Registry r;
  r.add(announcement("echoes", 1, {description("Echo", "echo")}));
  r.remove("echoes", "skill process echoes stopped answering");
  EXPECT_TRUE(r.find("Echo").empty());
  EXPECT_EQ(r.incarnation_of("echoes"), 0);
  EXPECT_EQ(r.gone("Echo"), "skill process echoes stopped answering");
  r.add(announcement("echoes", 2, {description("Echo", "echo")}));
  EXPECT_EQ(r.gone("Echo"), "");
}

TEST(Scope, RemapsComposeDownTheTreeAndSpecifiedValuesReachDescendants) {
  Scope root;
  auto pick = root.child({{"Target", "Object"}}, {});           // Pick's child MoveArm reads Target as Object
  auto move = pick->child({{"Goal", "Target"}}, {});            // and a grandchild reads Goal as that
  EXPECT_EQ(move->key("Goal"), "Object");
  EXPECT_EQ(move->key("Other"), "Other");
  auto fixed = root.child({}, {{"Object", value("Object", 3)}});  // a compound's specify
  auto under = fixed->child({{"Target", "Object"}}, {});
  ASSERT_NE(under->specified("Target"), nullptr);
  EXPECT_EQ(under->specified("Target")->values[0].i, 3);
  EXPECT_EQ(under->specified("Speed"), nullptr);
}

TEST(GatherParams, OrderIsSpecifiedStaticUnlessGivenBlackboardDefault) {
  auto d = description("Echo", "echo");
  d.params = {decl("N", skill_param_t::REQUIRED, {1}),   // static
              decl("M", skill_param_t::OPTIONAL, {2}),   // a default
              decl("K", skill_param_t::REQUIRED)};       // must be given
  d.num_params = 3;
  Blackboard bb;
  Scope root;
  std::string missing;
  auto ps = gather_params(d, root, bb, &missing);
  EXPECT_EQ(ps[0].values[0].i, 1);
  EXPECT_EQ(ps[1].values[0].i, 2);
  EXPECT_EQ(missing, "missing parameter K of Echo");
  bb.set("N", value("N", 9));  // a skill wrote N: the static value still wins
  bb.set("M", value("M", 8));  // the blackboard beats a default
  bb.give("K", value("K", 5));
  missing.clear();
  ps = gather_params(d, root, bb, &missing);
  EXPECT_EQ(ps[0].values[0].i, 1);
  EXPECT_EQ(ps[1].values[0].i, 8);
  EXPECT_EQ(ps[2].values[0].i, 5);
  EXPECT_EQ(missing, "");
  bb.give("N", value("N", 5));  // the user's value beats the static one
  ps = gather_params(d, root, bb, nullptr);
  EXPECT_EQ(ps[0].values[0].i, 5);
}

TEST(SameValues, ComparesByEncodingIncludingEmptiness) {
  EXPECT_TRUE(same_values(value("N", 1), value("N", 1)));
  EXPECT_FALSE(same_values(value("N", 1), value("N", 2)));
  Param emptied = value("N", 1);
  emptied.values.clear();
  EXPECT_FALSE(same_values(value("N", 1), emptied));  // an emptied value is a change
}

TEST(NodeConditions, ANodesConditionOrNeverJoinsTheSkillsOwn) {
  auto member = [](const std::string& label, const std::string& or_label) {
    skillbus_msgs::skill_condition_t c{};
    c.kind = "IsSpecified";
    c.label = label;
    c.subject = "Object";
    c.desired_state = true;
    c.or_label = or_label;
    return c;
  };
  skillbus_msgs::skill_description_t d{};
  d.pre = {member("A", "either"), member("B", "either")};
  d.num_pre = 2;
  skillbus_msgs::skill_tree_node_t n{};
  n.pre = {member("C", "either"), member("D", "either"), member("E", "")};
  n.num_pre = 3;
  add_node_conditions(d, n);
  ASSERT_EQ(d.num_pre, 5);
  EXPECT_EQ(d.pre[1].or_label, "either");
  EXPECT_NE(d.pre[2].or_label, d.pre[1].or_label);  // (A or B) and (C or D), not A or B or C or D
  EXPECT_EQ(d.pre[2].or_label, d.pre[3].or_label);
  EXPECT_EQ(d.pre[4].or_label, "");
}
