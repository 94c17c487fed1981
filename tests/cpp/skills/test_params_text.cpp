// The text of a primitive's parameters in the task's progress (skill_progress_t's
// params: "key=value,value" lines), as the console and the logs show it. Written without
// streams since 2026-12-03; the same text as before, which this pins.
#include <gtest/gtest.h>

#include <limits>

#include "blackboard.hpp"

using namespace skillbus::skills;
using skillbus_msgs::skill_value_t;

namespace {
skill_value_t value(int8_t type) {
  skill_value_t v{};
  v.type = type;
  return v;
}
skill_value_t f(double x) {
  auto v = value(skill_value_t::FLOAT);
  v.f = x;
  return v;
}
}  // namespace

TEST(ParamsText, FloatsAsAStreamWritesThem) {
  const std::pair<double, const char*> cases[] = {
      {0.0, "0"},          {0.1, "0.1"},          {-2.5, "-2.5"},        {0.425, "0.425"},
      {1.0 / 3, "0.333333"}, {123456789.0, "1.23457e+08"}, {1e-7, "1e-07"}, {100000, "100000"},
      {1e6, "1e+06"},      {std::numeric_limits<double>::infinity(), "inf"}, {-0.0, "-0"}};
  for (const auto& [x, text] : cases) EXPECT_EQ(value_text(f(x)), text) << x;
}

TEST(ParamsText, EveryTypeAndSeveralValues) {
  auto i = value(skill_value_t::INT);
  i.i = -42;
  auto s = value(skill_value_t::STRING);
  s.s = "red cube";
  auto b = value(skill_value_t::BOOL);
  b.b = true;
  auto e = value(skill_value_t::ELEMENT);
  e.element.id = "skiros:Cube-2";
  auto t = value(skill_value_t::ELEMENT);
  t.element.type = "skiros:Cube";  // (not grounded yet: its type)
  auto j = value(skill_value_t::JSON);
  j.s = "{\"a\": 1}";
  Param p1{}, p2{}, p3{};
  p1.key = "Object";
  p1.values = {e, t};
  p2.key = "Mixed";
  p2.values = {i, s, b, f(0.5), j, value(99)};
  p3.key = "Empty";
  EXPECT_EQ(params_text({p1, p2, p3}),
            "Object=skiros:Cube-2,skiros:Cube\nMixed=-42,red cube,true,0.5,{\"a\": 1},?\nEmpty=\n");
}
