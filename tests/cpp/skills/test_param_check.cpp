// The skill manager's parameter checks and grounding, without processes: a wrong value
// is an error naming it, never another value.
#include <gtest/gtest.h>

#include <cmath>

#include "conditions.hpp"
#include "grounding.hpp"
#include "param_check.hpp"
#include "wm/wm_test_util.hpp"

using namespace skillbus;
using namespace skillbus::skills;
using skillbus_msgs::skill_param_t;
using skillbus_msgs::skill_value_t;
namespace wt = skillbus::wm::test;

namespace {

wm::WorldStore demo_world() {
  wm::WorldStore w(wt::ontology());
  w.apply({wt::add(wt::element("skiros:Table-1", "skiros:Table", "table")),
           wt::add(wt::element("skiros:Cube-2", "skiros:Cube", "red", {{"skiros:PositionZ", {wm::Value(0.425)}}})),
           wt::add(wt::element("skiros:Cube-3", "skiros:Cube", "green")),
           wt::add(wt::element("skiros:Arm-8", "skiros:Arm", "arm")),
           wt::relate("skiros:Table-1", "skiros:contain", "skiros:Cube-2")});
  return w;
}

Param element_param(const std::string& key, const std::string& concept_name, const std::string& id,
                    int8_t kind = skill_param_t::REQUIRED) {
  Param p{};
  p.key = key;
  p.data_type = "element";
  p.concept = concept_name;
  p.param_type = kind;
  skill_value_t v{};
  v.type = skill_value_t::ELEMENT;
  v.element.id = id;
  v.element.type = concept_name;
  p.values = {v};
  p.num_values = 1;
  return p;
}

skillbus_msgs::skill_description_t echo() {
  skillbus_msgs::skill_description_t d{};
  d.type = "Echo";
  for (auto [key, type] : {std::pair{"N", "int"}, {"Flag", "bool"}, {"Gain", "float"}, {"Items", "list"}}) {
    Param p{};
    p.key = key;
    p.data_type = type;
    d.params.push_back(p);
  }
  d.num_params = static_cast<int32_t>(d.params.size());
  return d;
}

Param text(const std::string& key, const std::string& value) {
  Param p{};
  p.key = key;
  skill_value_t v{};
  v.type = skill_value_t::STRING;
  v.s = value;
  p.values = {v};
  p.num_values = 1;
  return p;
}

// A parameter with one typed value (data_type as given: "" for none).
Param valued(const std::string& key, const std::string& data_type, const skill_value_t& v) {
  Param p{};
  p.key = key;
  p.data_type = data_type;
  p.values = {v};
  p.num_values = 1;
  return p;
}

skill_value_t int_value(int64_t i) {
  skill_value_t v{};
  v.type = skill_value_t::INT;
  v.i = i;
  return v;
}

}  // namespace

TEST(ParamCheck, AMissingElementIsAnErrorNamingParameterIdAndType) {
  auto w = demo_world();
  std::vector<Param> ps{element_param("Object", "skiros:Product", "skiros:Cube-99")};
  EXPECT_EQ(check_elements(ps, w), "parameter Object: no element skiros:Cube-99 in the world model (expected a skiros:Product)");
}

TEST(ParamCheck, AnIdWithoutItsPrefixNamesTheElementMeant) {
  auto w = demo_world();
  std::vector<Param> ps{element_param("Object", "skiros:Product", "Cube-3")};
  EXPECT_NE(check_elements(ps, w).find("did you mean skiros:Cube-3?"), std::string::npos);
}

TEST(ParamCheck, AnElementOfAnotherConceptIsRefusedASubclassIsTaken) {
  auto w = demo_world();
  std::vector<Param> bad{element_param("Object", "skiros:Product", "skiros:Table-1")};
  EXPECT_EQ(check_elements(bad, w), "parameter Object: skiros:Table-1 is a skiros:Table, not a skiros:Product");
  std::vector<Param> good{element_param("Object", "skiros:Product", "skiros:Cube-2")};
  EXPECT_EQ(check_elements(good, w), "");
  ASSERT_EQ(good[0].values[0].element.num_properties, 1);  // the world's copy, with its properties
  EXPECT_EQ(good[0].values[0].element.properties[0].key, "skiros:PositionZ");
}

TEST(Grounding, AConcreteMissingIdIsNeverGrounded) {
  auto w = demo_world();
  std::vector<Param> ps{element_param("Object", "skiros:Product", "skiros:Cube-99")};
  EXPECT_FALSE(needs_grounding(ps));
}

TEST(Grounding, AnUnconstrainedRequiredElementIsGroundedOnlyWhenUnique) {
  auto w = demo_world();
  std::vector<Param> arm{element_param("Arm", "skiros:Arm", "")};
  EXPECT_EQ(ground(arm, {}, w), "");
  EXPECT_EQ(arm[0].values[0].element.id, "skiros:Arm-8");
  std::vector<Param> target{element_param("Target", "skiros:PhysicalObject", "")};
  const std::string err = ground(target, {}, w);
  EXPECT_NE(err.find("cannot ground parameter Target: 4 elements are a skiros:PhysicalObject"), std::string::npos) << err;
  std::vector<Param> inferred{element_param("Object", "skiros:Product", "", skill_param_t::INFERRED)};
  EXPECT_EQ(ground(inferred, {}, w), "");  // Inferred: the first that fits, as SkiROS2 does
  EXPECT_EQ(inferred[0].values[0].element.id, "skiros:Cube-2");
}

TEST(Grounding, APreConditionMakesTheChoice) {
  auto w = demo_world();
  std::vector<Param> ps{element_param("Table", "skiros:Table", "skiros:Table-1"),
                        element_param("Object", "skiros:Product", "")};
  Condition on_table{};
  on_table.kind = "Relation";
  on_table.label = "OnTable";
  on_table.owl = "skiros:contain";
  on_table.subject = "Table";
  on_table.object = "Object";
  on_table.desired_state = true;
  EXPECT_EQ(ground(ps, {on_table}, w), "");
  EXPECT_EQ(ps[1].values[0].element.id, "skiros:Cube-2");
}

TEST(ParamCheck, TextParsesStrictlyByType) {
  const auto d = echo();
  struct Row {
    const char* key;
    const char* text;
    bool ok;
  };
  for (const Row& r : {Row{"Flag", "true", true}, Row{"Flag", "TRUE", true}, Row{"Flag", "0", true},
                       Row{"Flag", "maybe", false}, Row{"Flag", "yes", false}, Row{"Flag", "", false},
                       Row{"N", "5", true}, Row{"N", "5.5", false}, Row{"N", "five", false},
                       Row{"Gain", "0.5", true}, Row{"Gain", "0.5x", false}, Row{"Items", "[1, 2]", true},
                       Row{"Items", "{\"a\": 1}", false}, Row{"Items", "[1,", false}}) {
    Param p = text(r.key, r.text);
    EXPECT_EQ(parse_text(d, p).empty(), r.ok) << r.key << "=" << r.text;
  }
  Param flag = text("Flag", "False");
  ASSERT_EQ(parse_text(d, flag), "");
  EXPECT_EQ(flag.values[0].type, skill_value_t::BOOL);
  EXPECT_FALSE(flag.values[0].b);
  Param nn = text("NN", "5");
  EXPECT_EQ(parse_text(d, nn), "Echo has no parameter NN (it has: N, Flag, Gain, Items)");
}

TEST(ParamCheck, GivenValuesMustHaveTheirParametersType) {
  const auto d = echo();
  Param n = text("N", "5");
  n.data_type = "int";  // a forged start: an int parameter carrying a string
  EXPECT_EQ(check_given(d, {n}), "parameter N of Echo is a int, not a str");
  Param gain{};
  gain.key = "Gain";
  gain.data_type = "float";
  skill_value_t i{};
  i.type = skill_value_t::INT;
  i.i = 2;
  gain.values = {i};
  EXPECT_EQ(check_given(d, {gain}), "");  // an int is a fine float
  EXPECT_EQ(check_given(d, {text("Nope", "1")}), "Echo has no parameter Nope (it has: N, Flag, Gain, Items)");
}

TEST(ParamCheck, ReturnedValuesAreTypedByTheDeclarationNotByThemselves) {
  const auto d = echo();
  Param n = text("N", "5");  // a reply that claims no data type: a str where N is an int
  EXPECT_EQ(check_returned(d, {n}), "parameter N as a str, where Echo declares a int");
  n.data_type = "int";  // nor one that claims the right type for the wrong value
  EXPECT_EQ(check_returned(d, {n}), "parameter N as a str, where Echo declares a int");
  EXPECT_EQ(check_returned(d, {text("Nope", "1")}), "a parameter Nope that Echo does not have (it has: N, Flag, Gain, Items)");
  Param gain{};
  gain.key = "Gain";
  skill_value_t i{};
  i.type = skill_value_t::INT;
  i.i = 2;
  gain.values = {i};
  Param emptied{};
  emptied.key = "N";  // a value taken away is the skill's to do
  EXPECT_EQ(check_returned(d, {gain, emptied}), "");
}

TEST(ParamCheck, ANonFiniteFloatIsRefusedGivenAsTextOrReturned) {
  // Before, a start with Gain=nan was acknowledged and queued, and only the skill
  // process's check of its START tick refused it.
  const auto d = echo();
  for (const char* t : {"nan", "inf", "-inf", "1e999"}) {
    Param p = text("Gain", t);
    EXPECT_EQ(parse_text(d, p), std::string("parameter Gain: '") + t + "' is not a finite float") << t;
  }
  skill_value_t f{};
  f.type = skill_value_t::FLOAT;
  f.f = std::nan("");
  const Param gain = valued("Gain", "float", f);
  EXPECT_EQ(check_given(d, {gain}), "parameter Gain of Echo: nan is not a finite number");
  EXPECT_EQ(check_returned(d, {gain}), "parameter Gain as nan, not a finite number");
}

TEST(ParamCheck, AValueWithoutItsDataTypeMustBeOneTextValue) {
  // A forged start whose value has no data type was read as its text: an int sent for a
  // string parameter became "", another value than the one sent.
  const auto d = echo();
  Param n = valued("N", "", int_value(5));
  EXPECT_EQ(parse_text(d, n), "parameter N: a value without its data type must be one text value, not 1 value(s) of type int");
  Param two = text("N", "5");
  two.values.push_back(two.values[0]);
  EXPECT_EQ(parse_text(d, two), "parameter N: a value without its data type must be one text value, not 2 value(s) of type str");
}

TEST(Conditions, WhatCannotBeJudgedFailsWhateverTheDesiredState) {
  auto w = demo_world();
  Condition not_holding{};
  not_holding.kind = "Relation";
  not_holding.label = "NotHolding";
  not_holding.owl = "skiros:contain";
  not_holding.subject = "Table";
  not_holding.object = "Object";
  not_holding.desired_state = false;
  std::vector<Param> gone{element_param("Table", "skiros:Table", "skiros:Table-1"),
                          element_param("Object", "skiros:Product", "skiros:Cube-99")};
  EXPECT_FALSE(check_conditions({not_holding}, gone, &w).ok);  // a missing element is no answer
  std::vector<Param> there{element_param("Table", "skiros:Table", "skiros:Table-1"),
                           element_param("Object", "skiros:Product", "skiros:Cube-3")};
  EXPECT_TRUE(check_conditions({not_holding}, there, &w).ok);   // Cube-3 is not on the table
  EXPECT_FALSE(check_conditions({not_holding}, there, nullptr).ok);  // no world model: cannot judge
  std::vector<Param> on{element_param("Table", "skiros:Table", "skiros:Table-1"),
                        element_param("Object", "skiros:Product", "skiros:Cube-2")};
  EXPECT_FALSE(check_conditions({not_holding}, on, &w).ok);     // Cube-2 is
}

TEST(ParamCheck, ASpecifiedListBecomesOneJsonListAndAWrongTypeIsNamed) {
  const auto d = echo();
  Param items = text("Items", "a");
  items.values.push_back(items.values[0]);
  items.values[1].s = "b";
  EXPECT_EQ(fit_specified(d, items), "");
  ASSERT_EQ(items.values.size(), 1u);
  EXPECT_EQ(items.values[0].s, "[\"a\",\"b\"]");
  Param n = text("N", "five");
  EXPECT_EQ(fit_specified(d, n), "parameter N of Echo is a int, not a str");
}
