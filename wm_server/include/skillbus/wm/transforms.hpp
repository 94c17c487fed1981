// Spatial reasoning: every element with pose properties (skiros:PositionX..Z,
// skiros:OrientationX..W) is posed relative to the element that contains it
// (skiros:contain), so the containment relation is the frame tree and moving a parent
// moves everything it contains. Elements without a pose sit at their parent's origin.
#pragma once

#include <Eigen/Geometry>
#include <string>

#include "skillbus/wm/store.hpp"

namespace skillbus::wm {

// Pose of `e` relative to its parent, from its properties (identity where absent).
Eigen::Isometry3d local_pose(const Element& e);
// The element that contains `id`, or "" at the root. Throws WmError if several do.
std::string parent_of(const WorldStore& store, const std::string& id);
// Pose of `id` in the root frame (the world). Throws WmError on a containment cycle.
Eigen::Isometry3d world_pose(const WorldStore& store, const std::string& id);
// Pose of `from` expressed in `to`. Each may be an element id or the skiros:FrameId of
// an element ("map" names the scene's frame). Throws WmError naming an unknown frame.
Eigen::Isometry3d transform(const WorldStore& store, const std::string& from, const std::string& to);

}  // namespace skillbus::wm
