// What the arm would touch at a joint configuration: the scene's fixtures (table, bin)
// and obstacles, which the world model knows, through DART's collision detection (FCL),
// and what a depth camera saw, as an occupancy map (voxels). A held object rides along
// as a box at the tool. DART stays in src/collision.cpp.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "skillbus/scene/scene.hpp"

namespace skillbus::motion {

// One contact: which part of the robot (a link's name, or "held object") touches what
// (a fixture's or obstacle's scene name, or "the occupancy map").
struct Touch {
  std::string part, body;
  bool obstacle = false;  // body is one of the scene's obstacles
  bool operator==(const Touch& o) const { return part == o.part && body == o.body; }
};

struct CollisionOptions {
  // Obstacles are checked grown by this much on every side: the arm follows its
  // trajectory within a few millimetres, and a swinging held object a little more.
  // Fixtures are not grown: the skills grasp on a table and place into a bin.
  double obstacle_margin = 0.03;  // m
};

class CollisionModel {
 public:
  // The scene's robot with that bus name ("": the one robot), its fixtures and obstacles;
  // throws scene::SceneError (a URDF DART cannot load).
  explicit CollisionModel(const scene::Scene& scene, const std::string& robot = "", CollisionOptions options = {});
  ~CollisionModel();
  CollisionModel(const CollisionModel&) = delete;
  CollisionModel& operator=(const CollisionModel&) = delete;

  // A box held at the tool centre point (its sides, m, in the tool frame); zero: none.
  void set_held(const Eigen::Vector3d& size);
  // Occupied voxels (their centres, world frame) of an occupancy map of that resolution,
  // checked as a DART VoxelGridShape; none: no map.
  void set_map(const std::vector<Eigen::Vector3d>& occupied, double resolution);
  size_t map_voxels() const;
  // Voxels within `radius` of `centre` leave the map (what a skill is about to grasp).
  void clear_map_around(const Eigen::Vector3d& centre, double radius);

  // Every contact of the arm (over its arm joints, in Kinematics' order) at q, in a fixed
  // order: by part, then by body.
  std::vector<Touch> touches(const Eigen::VectorXd& q) const;
  // No contact at q but those allowed (the contacts a move starts in: a held cube still on
  // its support may leave it; no new contact may begin).
  bool clear(const Eigen::VectorXd& q, const std::vector<Touch>& allowed = {}) const;
  // The same answer through DART's collision groups (group against group, with their broad
  // phase): what `clear` is checked against in the tests; a few times slower.
  bool clear_by_groups(const Eigen::VectorXd& q, const std::vector<Touch>& allowed = {}) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace skillbus::motion
