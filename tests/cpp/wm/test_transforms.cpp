#include <gtest/gtest.h>

#include <cmath>

#include "skillbus/wm/transforms.hpp"
#include "wm_test_util.hpp"

using namespace skillbus::wm;
using namespace skillbus::wm::test;

namespace {

std::map<std::string, std::vector<Value>> pose(double x, double y, double z, double yaw = 0) {
  return {{"skiros:PositionX", {x}},           {"skiros:PositionY", {y}},
          {"skiros:PositionZ", {z}},           {"skiros:OrientationX", {0.0}},
          {"skiros:OrientationY", {0.0}},      {"skiros:OrientationZ", {std::sin(yaw / 2)}},
          {"skiros:OrientationW", {std::cos(yaw / 2)}}};
}

}  // namespace

TEST(Transforms, ThroughAThreeLevelFrameTree) {
  WorldStore store(ontology());
  auto scene_props = pose(0, 0, 0);
  scene_props["skiros:FrameId"] = {std::string("map")};
  store.apply({add(element("skiros:Scene-0", "skiros:Scene", "", scene_props)),
               add(element("skiros:Table-1", "skiros:Table", "", pose(1, 0, 0, M_PI / 2))),
               add(element("skiros:LargeBox-2", "skiros:LargeBox", "", pose(0, 1, 0))),
               add(element("skiros:Cube-3", "skiros:Cube", "", pose(0, 0, 0.5))),
               relate("skiros:Scene-0", "skiros:contain", "skiros:Table-1"),
               relate("skiros:Table-1", "skiros:contain", "skiros:LargeBox-2"),
               relate("skiros:LargeBox-2", "skiros:contain", "skiros:Cube-3")});
  // The table is turned 90 degrees: the box's +y becomes the world's -x.
  Eigen::Vector3d p = world_pose(store, "skiros:Cube-3").translation();
  EXPECT_NEAR(p.x(), 0.0, 1e-12);
  EXPECT_NEAR(p.y(), 0.0, 1e-12);
  EXPECT_NEAR(p.z(), 0.5, 1e-12);
  p = transform(store, "skiros:Cube-3", "skiros:Table-1").translation();
  EXPECT_NEAR(p.x(), 0.0, 1e-12);
  EXPECT_NEAR(p.y(), 1.0, 1e-12);
  EXPECT_NEAR(p.z(), 0.5, 1e-12);
  p = transform(store, "map", "skiros:Cube-3").translation();  // a frame id works as well
  EXPECT_NEAR(p.z(), -0.5, 1e-12);

  // Moving the table moves what it contains.
  store.apply({Op{Op::UpdateElement, element("skiros:Table-1", "skiros:Table", "", pose(2, 0, 0, M_PI / 2)), {}}});
  EXPECT_NEAR(world_pose(store, "skiros:Cube-3").translation().x(), 1.0, 1e-12);
  EXPECT_THROW(transform(store, "skiros:Cube-3", "nowhere"), WmError);
}

TEST(Transforms, ACycleIsRefusedByTheStoreSoNoPoseIsEverAsked) {
  // (transforms.cpp still stops at a cycle; the store no longer lets one in)
  WorldStore store(ontology());
  EXPECT_THROW(
      store.apply({add(element("skiros:LargeBox-1", "skiros:LargeBox")), add(element("skiros:LargeBox-2", "skiros:LargeBox")),
                   relate("skiros:LargeBox-1", "skiros:contain", "skiros:LargeBox-2"),
                   relate("skiros:LargeBox-2", "skiros:contain", "skiros:LargeBox-1")}),
      WmError);
  EXPECT_EQ(store.version(), 0);
}

TEST(Transforms, AFrameNameTwoElementsCarryOrAnEmptyOneIsRefusedNamingThem) {
  // Before, the first carrier in id order was taken without a word (two cubes given one
  // frame name), and an empty name matched an element whose FrameId was "".
  WorldStore store(ontology());
  auto a = pose(0, 0, 0.5), b = pose(1, 0, 0.5), c = pose(0, 2, 0);
  a["skiros:FrameId"] = {std::string("tcp")};
  b["skiros:FrameId"] = {std::string("tcp")};
  c["skiros:FrameId"] = {std::string("")};
  store.apply({add(element("skiros:Cube-1", "skiros:Cube", "", a)), add(element("skiros:Cube-2", "skiros:Cube", "", b)),
               add(element("skiros:Table-3", "skiros:Table", "", c))});
  try {
    transform(store, "tcp", "skiros:Table-3");
    FAIL() << "an ambiguous frame was taken";
  } catch (const WmError& e) {
    EXPECT_EQ(std::string(e.what()), "frame 'tcp' is ambiguous: skiros:Cube-1, skiros:Cube-2 all carry it as their "
                                     "skiros:FrameId (give an element id)");
  }
  EXPECT_THROW(transform(store, "", "skiros:Cube-1"), WmError);
  EXPECT_NEAR(transform(store, "skiros:Cube-2", "skiros:Cube-1").translation().x(), 1.0, 1e-12);  // ids still work
}
