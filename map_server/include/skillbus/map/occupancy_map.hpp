// The occupancy map: an OctoMap octree (liboctomap) of the space the cameras have seen,
// each voxel free, occupied or unknown. Clouds are inserted with free-space ray casting
// (every voxel a ray crosses is more likely free, the voxel it ends in more likely
// occupied). OctoMap stays behind this header (pimpl); docs/perception.md.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "skillbus/digest.hpp"

namespace skillbus::map {

using Vec3 = std::array<double, 3>;

enum class Cell { Free, Occupied, Unknown };

// Voxels of the finest resolution inside a box, by state.
struct BoxCounts {
  int64_t occupied = 0, free = 0, unknown = 0;
};

class OccupancyMap {
 public:
  // resolution: the edge of a voxel (m), > 0; throws std::invalid_argument.
  explicit OccupancyMap(double resolution = 0.01);
  ~OccupancyMap();
  OccupancyMap(OccupancyMap&&) noexcept;
  OccupancyMap& operator=(OccupancyMap&&) noexcept;

  // One sensor reading from `origin`: `hits` are surfaces seen (free up to them, occupied
  // where they are), `misses` are directions where nothing was seen within max_range
  // (free up to max_range; any point along the ray beyond max_range will do).
  void insert(const std::vector<Vec3>& hits, const std::vector<Vec3>& misses, const Vec3& origin, double max_range);

  Cell state(const Vec3& p) const;
  // Throws std::invalid_argument for a box with lo > hi, or of more than kMaxBoxVoxels.
  BoxCounts box(const Vec3& lo, const Vec3& hi) const;
  // The centres of the occupied voxels (finest resolution) in the box, in key order (x,
  // then y, then z), at most `limit`; `more` says whether some were left out. Throws
  // std::invalid_argument as box() does.
  std::vector<Vec3> occupied(const Vec3& lo, const Vec3& hi, size_t limit, bool* more = nullptr) const;
  // The area (m2) of the box's footprint (x, y at the map's resolution) whose voxels in
  // the box are all known free: where something of the box's height fits, by what the
  // cameras have seen. `area`, if given, gets the footprint's whole area.
  double free_area(const Vec3& lo, const Vec3& hi, double* area = nullptr) const;

  // Where a footprint (x, y sides, m) with `clearance` around it fits in the box: the
  // centres (at the box's bottom) on a grid of the map's resolution, row by row from the
  // box's low x and y corner, whose footprint-plus-clearance column over the box's height
  // has no occupied voxel and at most `max_unknown` of its voxels unknown. At most
  // `limit`. Throws std::invalid_argument as box() does, or for a footprint <= 0.
  std::vector<Vec3> free_spots(const Vec3& lo, const Vec3& hi, double footprint_x, double footprint_y,
                               double clearance, double max_unknown = 0.2, size_t limit = 64) const;

  // OctoMap's binary format (.bt: each voxel free or occupied, the probabilities
  // thresholded). Throw std::runtime_error naming the file.
  void save(const std::string& path) const;
  static OccupancyMap load(const std::string& path);
  void clear();

  double resolution() const;
  size_t leaves() const;
  // SHA-256 of the map in .bt form: the same map gives the same digest.
  Digest digest() const;

  static constexpr int64_t kMaxBoxVoxels = 20'000'000;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace skillbus::map
