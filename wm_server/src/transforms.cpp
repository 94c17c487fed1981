#include "skillbus/wm/transforms.hpp"

#include <set>

namespace skillbus::wm {

namespace {

double number(const Element& e, const char* key, double fallback) {
  auto it = e.properties.find(key);
  if (it == e.properties.end() || it->second.empty()) return fallback;
  const Value& v = it->second.front();
  if (auto d = std::get_if<double>(&v)) return *d;
  if (auto i = std::get_if<int64_t>(&v)) return static_cast<double>(*i);
  return fallback;
}

std::string resolve_frame(const WorldStore& store, const std::string& name) {
  if (name.empty()) throw WmError("a frame is needed: an element id or an element's skiros:FrameId");
  if (store.get(name)) return name;
  // Every element that carries the name: with two (two cubes given one frame name), the
  // first in id order was taken without a word, the other's pose never considered.
  std::vector<std::string> carriers;
  for (const auto& [id, e] : store.elements()) {
    auto it = e.properties.find("skiros:FrameId");
    if (it != e.properties.end() && !it->second.empty() && it->second.front() == Value(name)) carriers.push_back(id);
  }
  if (carriers.size() == 1) return carriers.front();
  if (carriers.empty())
    throw WmError("unknown frame '" + name + "' (neither an element id nor an element's skiros:FrameId)");
  std::string ids;
  for (const auto& id : carriers) ids += (ids.empty() ? "" : ", ") + id;
  throw WmError("frame '" + name + "' is ambiguous: " + ids + " all carry it as their skiros:FrameId (give an element id)");
}

}  // namespace

Eigen::Isometry3d local_pose(const Element& e) {
  Eigen::Quaterniond q(number(e, "skiros:OrientationW", 1.0), number(e, "skiros:OrientationX", 0.0),
                       number(e, "skiros:OrientationY", 0.0), number(e, "skiros:OrientationZ", 0.0));
  if (q.norm() < 1e-12) q = Eigen::Quaterniond::Identity();
  q.normalize();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = q.toRotationMatrix();
  t.translation() = Eigen::Vector3d(number(e, "skiros:PositionX", 0.0), number(e, "skiros:PositionY", 0.0),
                                    number(e, "skiros:PositionZ", 0.0));
  return t;
}

std::string parent_of(const WorldStore& store, const std::string& id) {
  std::string parent;
  for (const auto& r : store.relations("", "skiros:contain", id)) {
    if (r.object != id) continue;
    if (!parent.empty() && parent != r.subject)
      throw WmError(id + " is contained by both " + parent + " and " + r.subject + ": its frame is ambiguous");
    parent = r.subject;
  }
  return parent;
}

Eigen::Isometry3d world_pose(const WorldStore& store, const std::string& id) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  std::set<std::string> seen;
  for (std::string cur = id; !cur.empty(); cur = parent_of(store, cur)) {
    if (!seen.insert(cur).second) throw WmError("containment cycle through " + cur);
    const Element* e = store.get(cur);
    if (!e) throw WmError("no element " + cur);
    pose = local_pose(*e) * pose;
  }
  return pose;
}

Eigen::Isometry3d transform(const WorldStore& store, const std::string& from, const std::string& to) {
  const std::string f = resolve_frame(store, from), t = resolve_frame(store, to);
  return world_pose(store, t).inverse() * world_pose(store, f);
}

}  // namespace skillbus::wm
