// A compound without hold- or post-conditions does not gather its parameters at every
// tick (each element re-read from the world model), but the blackboard must end as if it
// had: write_static_params writes exactly what gather_params writes.
#include <gtest/gtest.h>

#include "skill_params.hpp"

using namespace skillbus;
using namespace skillbus::skills;
using skillbus_msgs::skill_param_t;
using skillbus_msgs::skill_value_t;

namespace {

Param declared(const std::string& key, const std::string& type, int8_t kind, double value) {
  Param p{};
  p.key = key;
  p.data_type = type;
  p.param_type = kind;
  skill_value_t v{};
  if (type == "element") {
    v.type = skill_value_t::ELEMENT;
    v.element.type = "skiros:Cube";
  } else {
    v.type = skill_value_t::FLOAT;
    v.f = value;
  }
  p.defaults = {v};
  p.num_defaults = 1;
  return p;
}

skillbus_msgs::skill_description_t description() {
  skillbus_msgs::skill_description_t d{};
  d.type = "Stack";
  d.params = {declared("Speed", "float", skill_param_t::REQUIRED, 0.5),      // static
              declared("Gain", "float", skill_param_t::REQUIRED, 2.0),       // static, but the user gave it
              declared("Height", "float", skill_param_t::REQUIRED, 0.1),     // fixed by the parent
              declared("Object", "element", skill_param_t::REQUIRED, 0),     // an element: grounded, never static
              declared("Margin", "float", skill_param_t::OPTIONAL, 0.01)};   // optional: a default, not static
  d.num_params = static_cast<int32_t>(d.params.size());
  return d;
}

std::string encoded(const Blackboard& bb) {
  std::string out;
  for (const auto& [key, p] : bb.all()) {
    Bytes b = encode_msg(static_cast<const skill_param_t&>(p));
    out += key + "=" + std::string(b.begin(), b.end()) + ";";
  }
  return out;
}

}  // namespace

TEST(StaticParams, WrittenExactlyAsGatheringWritesThem) {
  const auto root = std::make_shared<Scope>();
  Param height = declared("Height", "float", skill_param_t::REQUIRED, 0.3);
  height.values = height.defaults;
  height.num_values = 1;
  const auto scope = root->child({{"Speed", "stack_speed"}}, {{"Height", height}});
  Param gain = declared("Gain", "float", skill_param_t::REQUIRED, 7.0);
  gain.values = gain.defaults;
  gain.num_values = 1;

  Blackboard gathered, written;
  for (Blackboard* bb : {&gathered, &written}) {
    bb->give("Gain", gain);
    Param other = gain;
    other.key = "Elsewhere";
    bb->set("Elsewhere", other);  // (what the blackboard held before stays)
  }
  gather_params(description(), *scope, gathered, nullptr, nullptr);
  write_static_params(description(), *scope, written);

  EXPECT_EQ(encoded(written), encoded(gathered));
  ASSERT_TRUE(written.has("stack_speed"));  // under the parent's name for it
  EXPECT_EQ(written.get("stack_speed")->values.at(0).f, 0.5);
  EXPECT_EQ(written.get("Gain")->values.at(0).f, 7.0);  // the user's value stays
  EXPECT_FALSE(written.has("Height") || written.has("Object") || written.has("Margin") || written.has("Speed"));
}

TEST(StaticParams, AStaticValueChangedMeanwhileIsWrittenBackAsEveryTickWrites) {
  const auto scope = std::make_shared<Scope>();
  Blackboard bb;
  write_static_params(description(), *scope, bb);
  Param changed = *bb.get("Speed");
  changed.values.at(0).f = 9.0;
  bb.set("Speed", changed);  // (a child wrote it)
  write_static_params(description(), *scope, bb);
  EXPECT_EQ(bb.get("Speed")->values.at(0).f, 0.5);
}
