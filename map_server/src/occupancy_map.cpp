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
std::pair<octomap::OcTreeKey, octomap::OcTreeKey> keys_of(const octomap::OcTree& t, const Vec3& lo, const Vec3& hi) {
  for (int i = 0; i < 3; ++i)
    if (!(lo[i] <= hi[i])) throw std::invalid_argument("the box's min must not be above its max on any axis");
  octomap::OcTreeKey a, b;
  if (!t.coordToKeyChecked(pt(lo), a) || !t.coordToKeyChecked(pt(hi), b))
    throw std::invalid_argument("the box reaches outside the map's range");
  return {a, b};
}

int64_t voxels_between(const octomap::OcTreeKey& a, const octomap::OcTreeKey& b) {
  int64_t n = 1;
  for (int i = 0; i < 3; ++i) n *= static_cast<int64_t>(b[i]) - a[i] + 1;
  return n;
}

// keys_of, and the box at most kMaxBoxVoxels.
std::pair<octomap::OcTreeKey, octomap::OcTreeKey> key_box(const octomap::OcTree& t, const Vec3& lo, const Vec3& hi) {
  const auto [a, b] = keys_of(t, lo, hi);
  const int64_t n = voxels_between(a, b);
  if (n > OccupancyMap::kMaxBoxVoxels)
    throw std::invalid_argument("the box holds " + std::to_string(n) + " voxels; at most " +
                                std::to_string(OccupancyMap::kMaxBoxVoxels) + " are looked at (ask for a smaller box)");
  return {a, b};
}

// Columns of the summed-area tables below that free_spots and free_area build at a time
// (32 KB): a box is walked in bands of rows of about this many columns.
constexpr int64_t kBandColumns = int64_t{1} << 12;

// How many voxels of each column (x, y) of the keys a..b, between a's and b's z, are
// occupied and free, summed over rectangles of columns in O(1) (summed-area tables). The
// tree is walked once over the whole box: each of its voxels is looked at once, however
// many rectangles are asked for. 8 bytes a column.
class ColumnSums {
 public:
  ColumnSums(const octomap::OcTree& t, const octomap::OcTreeKey& a, const octomap::OcTreeKey& b)
      : a_(a), b_(b), nx_(b[0] - a[0] + 1), ny_(b[1] - a[1] + 1),
        occupied_((nx_ + 1) * (ny_ + 1), 0), free_((nx_ + 1) * (ny_ + 1), 0) {
    const unsigned depth = t.getTreeDepth();
    for (auto it = t.begin_leafs_bbx(a, b); it != t.end_leafs_bbx(); ++it) {
      // A leaf may be coarser than a voxel: each of its columns in the box gets the
      // voxels it shares with the box's height.
      const int64_t span = int64_t{1} << (depth - it.getDepth());
      const octomap::OcTreeKey k = it.getIndexKey();  // the leaf's lowest key
      const int64_t z = std::max<int64_t>(0, std::min<int64_t>(k[2] + span - 1, b[2]) - std::max<int64_t>(k[2], a[2]) + 1);
      auto& table = t.isNodeOccupied(*it) ? occupied_ : free_;
      for (int64_t x = std::max<int64_t>(k[0], a[0]); x <= std::min<int64_t>(k[0] + span - 1, b[0]); ++x)
        for (int64_t y = std::max<int64_t>(k[1], a[1]); y <= std::min<int64_t>(k[1] + span - 1, b[1]); ++y)
          table[at(x - a[0] + 1, y - a[1] + 1)] += static_cast<uint32_t>(z);
    }
    for (auto* table : {&occupied_, &free_})
      for (int64_t i = 1; i <= nx_; ++i)
        for (int64_t j = 1; j <= ny_; ++j)
          (*table)[at(i, j)] += (*table)[at(i - 1, j)] + (*table)[at(i, j - 1)] - (*table)[at(i - 1, j - 1)];
  }

  // Whether the columns of keys lo..hi lie within this box's (x, y), with its z.
  bool covers(const octomap::OcTreeKey& lo, const octomap::OcTreeKey& hi) const {
    return lo[0] >= a_[0] && hi[0] <= b_[0] && lo[1] >= a_[1] && hi[1] <= b_[1] && lo[2] == a_[2] && hi[2] == b_[2];
  }

  // What box(lo, hi) counts, for keys the box covers.
  BoxCounts counts(const octomap::OcTreeKey& lo, const octomap::OcTreeKey& hi) const {
    BoxCounts c;
    c.occupied = rect(occupied_, lo, hi);
    c.free = rect(free_, lo, hi);
    c.unknown = voxels_between(lo, hi) - c.occupied - c.free;
    return c;
  }

 private:
  size_t at(int64_t i, int64_t j) const { return static_cast<size_t>(i * (ny_ + 1) + j); }
  int64_t rect(const std::vector<uint32_t>& t, const octomap::OcTreeKey& lo, const octomap::OcTreeKey& hi) const {
    const int64_t x0 = lo[0] - a_[0], x1 = hi[0] - a_[0] + 1, y0 = lo[1] - a_[1], y1 = hi[1] - a_[1] + 1;
    // (unsigned wrap-around cancels out: every sum fits, the box has at most ~kMaxBoxVoxels)
    return static_cast<int64_t>(static_cast<uint32_t>(t[at(x1, y1)] - t[at(x0, y1)] - t[at(x1, y0)] + t[at(x0, y0)]));
  }

  octomap::OcTreeKey a_, b_;
  int64_t nx_, ny_;
  std::vector<uint32_t> occupied_, free_;
};

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
  const int64_t nx = static_cast<int64_t>(b[0]) - a[0] + 1, ny = static_cast<int64_t>(b[1]) - a[1] + 1;
  const int64_t height = static_cast<int64_t>(b[2]) - a[2] + 1;
  // A column is free when all its voxels in the box are known free: counted from one walk
  // over the box in bands of rows (one search of the tree per voxel was up to
  // kMaxBoxVoxels searches, seconds, in a lockstep frame).
  const int64_t rows = std::max<int64_t>(1, kBandColumns / nx);
  int64_t free_columns = 0;
  for (int64_t y0 = 0; y0 < ny; y0 += rows) {
    octomap::OcTreeKey ba = a, bb = b;
    ba[1] = static_cast<octomap::key_type>(a[1] + y0);
    bb[1] = static_cast<octomap::key_type>(a[1] + std::min(ny, y0 + rows) - 1);
    const ColumnSums columns(t, ba, bb);
    for (int64_t x = 0; x < nx; ++x)
      for (int64_t y = ba[1]; y <= bb[1]; ++y) {
        octomap::OcTreeKey k0 = ba, k1 = ba;
        k0[0] = k1[0] = static_cast<octomap::key_type>(a[0] + x);
        k0[1] = k1[1] = static_cast<octomap::key_type>(y);
        k1[2] = b[2];
        free_columns += columns.counts(k0, k1).free == height;
      }
  }
  if (area) *area = static_cast<double>(nx * ny) * cell;
  return static_cast<double>(free_columns) * cell;
}

std::vector<Vec3> OccupancyMap::free_spots(const Vec3& lo, const Vec3& hi, double footprint_x, double footprint_y,
                                           double clearance, double max_unknown, size_t limit) const {
  if (!(footprint_x > 0) || !(footprint_y > 0) || !(clearance >= 0) || !std::isfinite(footprint_x + footprint_y + clearance))
    throw std::invalid_argument("free_spots: the footprint must be > 0 and the clearance >= 0 (m)");
  const auto& t = impl_->tree;
  key_box(t, lo, hi);  // (the same checks as a box)
  const double r = resolution(), hx = footprint_x / 2 + clearance, hy = footprint_y / 2 + clearance;
  std::vector<Vec3> out;
  // Centres whose footprint and clearance lie inside the box, a voxel apart. (Compared as
  // doubles first: a huge footprint's negative count would not fit an int.)
  const double fx = std::floor((hi[0] - lo[0] - 2 * hx) / r + 1e-9), fy = std::floor((hi[1] - lo[1] - 2 * hy) / r + 1e-9);
  if (!(fx >= 0) || !(fy >= 0) || limit == 0) return out;
  const int nx = static_cast<int>(fx), ny = static_cast<int>(fy);  // (at most the box's voxels a side)
  const auto centre = [&](int i, int j) { return std::array<double, 2>{lo[0] + hx + i * r, lo[1] + hy + j * r}; };
  const auto column_box = [&](const std::array<double, 2>& c) {
    return std::pair<Vec3, Vec3>{{c[0] - hx, c[1] - hy, lo[2]}, {c[0] + hx, c[1] + hy, hi[2]}};
  };
  // Every centre's column box, counted as box() counts it (the same keys), from walks over
  // the boxes' union: one box() per centre was the centres times the footprint's voxels,
  // which kMaxBoxVoxels did not bound (a 2 x 2 m box, 1 cm voxels, a 10 cm footprint:
  // 36,000 boxes of 1,000 voxels). In bands of rows of centres, each band's union from its
  // first and last centre's corners (keys grow with the coordinates): tables of about
  // kBandColumns columns, a box walked about once (at most twice, with bands as deep
  // as the footprint), and no band past the one that reaches `limit`.
  const auto [row_lo, row_hi] = keys_of(t, column_box(centre(0, 0)).first, column_box(centre(nx, 0)).second);
  const int64_t columns_x = row_hi[0] - row_lo[0] + 1, footprint_rows = row_hi[1] - row_lo[1] + 1;
  const int rows = static_cast<int>(std::min<int64_t>(ny + 1, std::max(footprint_rows, kBandColumns / columns_x)));
  for (int j0 = 0; j0 <= ny && out.size() < limit; j0 += rows) {
    const int j1 = std::min(ny, j0 + rows - 1);
    const auto [ua, ub] = keys_of(t, column_box(centre(0, j0)).first, column_box(centre(nx, j1)).second);
    const ColumnSums columns(t, ua, ub);
    for (int j = j0; j <= j1 && out.size() < limit; ++j)
      for (int i = 0; i <= nx && out.size() < limit; ++i) {
        const auto c = centre(i, j);
        const auto [blo, bhi] = column_box(c);
        const auto [ka, kb] = key_box(t, blo, bhi);
        const BoxCounts n = columns.covers(ka, kb) ? columns.counts(ka, kb) : box(blo, bhi);
        const int64_t all = n.occupied + n.free + n.unknown;
        if (n.occupied == 0 && all > 0 && n.unknown <= max_unknown * all) out.push_back({c[0], c[1], lo[2]});
      }
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
