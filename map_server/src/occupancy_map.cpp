#include "skillbus/map/occupancy_map.hpp"

#include <array>

#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace skillbus::map {

struct OccupancyMap::Impl {
  explicit Impl(double resolution) : tree(resolution) {}
  octomap::OcTree tree;
};

namespace {

octomap::point3d pt(const Vec3& v) {
  return octomap::point3d(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]));
}

// The keys of the voxels holding lo and hi, checked to be in the map's range.
std::pair<octomap::OcTreeKey, octomap::OcTreeKey> key_box(const octomap::OcTree& t, const Vec3& lo, const Vec3& hi) {
  for (int i = 0; i < 3; ++i)
    if (!(lo[i] <= hi[i])) throw std::invalid_argument("the box's min must not be above its max on any axis");
  octomap::OcTreeKey a, b;
  if (!t.coordToKeyChecked(pt(lo), a) || !t.coordToKeyChecked(pt(hi), b))
    throw std::invalid_argument("the box reaches outside the map's range");
  int64_t n = 1;
  for (int i = 0; i < 3; ++i) n *= static_cast<int64_t>(b[i]) - a[i] + 1;
  if (n > OccupancyMap::kMaxBoxVoxels)
    throw std::invalid_argument("the box holds " + std::to_string(n) + " voxels; at most " +
                                std::to_string(OccupancyMap::kMaxBoxVoxels) + " are looked at (ask for a smaller box)");
  return {a, b};
}

}  // namespace

OccupancyMap::OccupancyMap(double resolution) {
  if (!(resolution > 0) || !std::isfinite(resolution)) throw std::invalid_argument("the map's resolution must be > 0");
  impl_ = std::make_unique<Impl>(resolution);
}

OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

void OccupancyMap::insert(const std::vector<Vec3>& hits, const std::vector<Vec3>& misses, const Vec3& origin,
                          double max_range) {
  octomap::Pointcloud cloud;
  cloud.reserve(hits.size() + misses.size());
  for (const auto& h : hits) cloud.push_back(pt(h));
  for (const auto& m : misses) cloud.push_back(pt(m));
  // Beams longer than max_range are cut there and mark only free space: the misses.
  // (OctoMap without OpenMP, as Debian builds it: the update does not depend on threads.)
  // Lazy: the inner nodes are brought up to date once, after every voxel is (for each
  // voxel touched, not once per ray).
  impl_->tree.insertPointCloud(cloud, pt(origin), max_range, true, true);
  impl_->tree.updateInnerOccupancy();
}

Cell OccupancyMap::state(const Vec3& p) const {
  const octomap::OcTreeNode* n = impl_->tree.search(pt(p));
  if (n == nullptr) return Cell::Unknown;
  return impl_->tree.isNodeOccupied(n) ? Cell::Occupied : Cell::Free;
}

BoxCounts OccupancyMap::box(const Vec3& lo, const Vec3& hi) const {
  const auto& t = impl_->tree;
  const auto [a, b] = key_box(t, lo, hi);
  BoxCounts c;
  int64_t total = 1;
  for (int i = 0; i < 3; ++i) total *= static_cast<int64_t>(b[i]) - a[i] + 1;
  // A leaf may be coarser than a voxel: count the voxels it shares with the box.
  const unsigned depth = t.getTreeDepth();
  for (auto it = t.begin_leafs_bbx(a, b); it != t.end_leafs_bbx(); ++it) {
    const int64_t span = int64_t{1} << (depth - it.getDepth());
    const octomap::OcTreeKey k = it.getIndexKey();  // the leaf's lowest key
    int64_t shared = 1;
    for (int i = 0; i < 3; ++i) {
      const int64_t from = std::max<int64_t>(k[i], a[i]), to = std::min<int64_t>(k[i] + span - 1, b[i]);
      shared *= std::max<int64_t>(0, to - from + 1);
    }
    (t.isNodeOccupied(*it) ? c.occupied : c.free) += shared;
  }
  c.unknown = total - c.occupied - c.free;
  return c;
}

std::vector<Vec3> OccupancyMap::occupied(const Vec3& lo, const Vec3& hi, size_t limit, bool* more) const {
  const auto& t = impl_->tree;
  const auto [a, b] = key_box(t, lo, hi);
  const unsigned depth = t.getTreeDepth();
  std::vector<std::array<unsigned, 3>> keys;
  for (auto it = t.begin_leafs_bbx(a, b); it != t.end_leafs_bbx(); ++it) {
    if (!t.isNodeOccupied(*it)) continue;
    const unsigned span = 1u << (depth - it.getDepth());  // a coarser leaf: each of its voxels in the box
    const octomap::OcTreeKey k = it.getIndexKey();
    for (unsigned x = std::max<unsigned>(k[0], a[0]); x <= std::min<unsigned>(k[0] + span - 1, b[0]); ++x)
      for (unsigned y = std::max<unsigned>(k[1], a[1]); y <= std::min<unsigned>(k[1] + span - 1, b[1]); ++y)
        for (unsigned z = std::max<unsigned>(k[2], a[2]); z <= std::min<unsigned>(k[2] + span - 1, b[2]); ++z)
          keys.push_back({x, y, z});
  }
  std::sort(keys.begin(), keys.end());  // the order of the keys, not of the tree's walk
  if (more) *more = keys.size() > limit;
  if (keys.size() > limit) keys.resize(limit);
  std::vector<Vec3> out;
  out.reserve(keys.size());
  for (const auto& k : keys) {
    const octomap::point3d c = t.keyToCoord(octomap::OcTreeKey(static_cast<octomap::key_type>(k[0]),
                                                               static_cast<octomap::key_type>(k[1]),
                                                               static_cast<octomap::key_type>(k[2])));
    out.push_back({c.x(), c.y(), c.z()});
  }
  return out;
}

double OccupancyMap::free_area(const Vec3& lo, const Vec3& hi, double* area) const {
  const auto& t = impl_->tree;
  const auto [a, b] = key_box(t, lo, hi);
  const double cell = t.getResolution() * t.getResolution();
  int64_t free_columns = 0, columns = 0;
  for (unsigned x = a[0]; x <= b[0]; ++x)
    for (unsigned y = a[1]; y <= b[1]; ++y) {
      ++columns;
      bool all_free = true;
      for (unsigned z = a[2]; z <= b[2] && all_free; ++z) {
        const octomap::OcTreeNode* n = t.search(octomap::OcTreeKey(x, y, z));
        all_free = n != nullptr && !t.isNodeOccupied(n);
      }
      free_columns += all_free;
    }
  if (area) *area = columns * cell;
  return free_columns * cell;
}

std::vector<Vec3> OccupancyMap::free_spots(const Vec3& lo, const Vec3& hi, double footprint_x, double footprint_y,
                                           double clearance, double max_unknown, size_t limit) const {
  if (!(footprint_x > 0) || !(footprint_y > 0) || !(clearance >= 0) || !std::isfinite(footprint_x + footprint_y + clearance))
    throw std::invalid_argument("free_spots: the footprint must be > 0 and the clearance >= 0 (m)");
  key_box(impl_->tree, lo, hi);  // (the same checks as a box)
  const double r = resolution(), hx = footprint_x / 2 + clearance, hy = footprint_y / 2 + clearance;
  std::vector<Vec3> out;
  // Centres whose footprint and clearance lie inside the box, a voxel apart.
  const int nx = static_cast<int>(std::floor((hi[0] - lo[0] - 2 * hx) / r + 1e-9));
  const int ny = static_cast<int>(std::floor((hi[1] - lo[1] - 2 * hy) / r + 1e-9));
  for (int j = 0; j <= ny && out.size() < limit; ++j)
    for (int i = 0; i <= nx && out.size() < limit; ++i) {
      const double x = lo[0] + hx + i * r, y = lo[1] + hy + j * r;
      const BoxCounts c = box({x - hx, y - hy, lo[2]}, {x + hx, y + hy, hi[2]});
      const int64_t all = c.occupied + c.free + c.unknown;
      if (c.occupied == 0 && all > 0 && c.unknown <= max_unknown * all) out.push_back({x, y, lo[2]});
    }
  return out;
}

void OccupancyMap::save(const std::string& path) const {
  if (!impl_->tree.writeBinary(path)) throw std::runtime_error("cannot write the map to " + path);
}

OccupancyMap OccupancyMap::load(const std::string& path) {
  octomap::OcTree probe(0.1);
  if (!probe.readBinary(path)) throw std::runtime_error("cannot read a binary OctoMap (.bt) from " + path);
  OccupancyMap m(probe.getResolution());
  m.impl_->tree.swapContent(probe);
  return m;
}

void OccupancyMap::clear() { impl_->tree.clear(); }
double OccupancyMap::resolution() const { return impl_->tree.getResolution(); }
size_t OccupancyMap::leaves() const { return impl_->tree.getNumLeafNodes(); }

Digest OccupancyMap::digest() const {
  std::ostringstream out;
  impl_->tree.writeBinaryConst(out);
  const std::string s = out.str();
  Sha256 h;
  h.update(s.data(), s.size());
  return h.finish();
}

}  // namespace skillbus::map
