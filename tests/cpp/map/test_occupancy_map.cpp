// The occupancy map alone: a sensor 1 m over a floor sees it; the floor's voxels become
// occupied, the space above free, what is under it stays unknown; box counts, the free
// area of a region, rays without a return, and the .bt round trip.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <random>

#include <unistd.h>

#include "skillbus/map/occupancy_map.hpp"

using namespace skillbus::map;

namespace {
// A grid of returns on the floor z = 0 over x, y in [-0.3, 0.3], seen from (0, 0, 1); a
// 10 cm cube's top (z = 0.1) replaces the floor over x, y in [0.1, 0.2].
std::vector<Vec3> floor_with_a_block() {
  std::vector<Vec3> hits;
  for (double x = -0.3; x <= 0.3001; x += 0.005)
    for (double y = -0.3; y <= 0.3001; y += 0.005) {
      const bool on_block = x >= 0.1 && x <= 0.2 && y >= 0.1 && y <= 0.2;
      hits.push_back({x, y, on_block ? 0.1 : 0.0});
    }
  return hits;
}
const Vec3 kOrigin{0, 0, 1};
}  // namespace

TEST(OccupancyMap, WhatASensorSawIsOccupiedTheWayToItFreeAndBehindItUnknown) {
  OccupancyMap m(0.01);
  m.insert(floor_with_a_block(), {}, kOrigin, 3.0);
  EXPECT_EQ(m.state({0.0, 0.0, 0.001}), Cell::Occupied);   // the floor
  EXPECT_EQ(m.state({0.15, 0.15, 0.105}), Cell::Occupied);  // the block's top (its voxel: z 0.10-0.11)
  EXPECT_EQ(m.state({0.0, 0.0, 0.5}), Cell::Free);          // between sensor and floor
  EXPECT_EQ(m.state({0.15, 0.15, 0.3}), Cell::Free);        // above the block
  EXPECT_EQ(m.state({0.0, 0.0, -0.2}), Cell::Unknown);      // under the floor
  EXPECT_EQ(m.state({0.15, 0.15, 0.05}), Cell::Unknown);    // inside the block, never seen
  EXPECT_EQ(m.state({2.0, 2.0, 0.5}), Cell::Unknown);       // out of view
}

TEST(OccupancyMap, BoxCountsAndTheFreeAreaOfARegion) {
  OccupancyMap m(0.01);
  m.insert(floor_with_a_block(), {}, kOrigin, 3.0);
  // A 20 x 20 cm slab 2-6 cm over the floor, around the block: free except where the block is.
  const Vec3 lo{0.0, 0.0, 0.021}, hi{0.199, 0.199, 0.059};
  const BoxCounts c = m.box(lo, hi);
  EXPECT_EQ(c.occupied + c.free + c.unknown, 20 * 20 * 4);
  EXPECT_EQ(c.occupied, 0);
  EXPECT_GT(c.unknown, 80);  // the block's inside, 10 x 10 x 4 voxels (its edges blur a little)
  double area = 0;
  const double free = m.free_area(lo, hi, &area);
  EXPECT_NEAR(area, 0.04, 1e-9);
  EXPECT_NEAR(free, 0.04 - 0.01, 0.003);  // the block's 10 x 10 cm are not free
  // The floor itself: occupied voxels.
  EXPECT_GT(m.box({-0.2, -0.2, 0.0001}, {0.0, 0.0, 0.009}).occupied, 300);
}

TEST(OccupancyMap, TheOccupiedVoxelsOfABoxAreListedInKeyOrder) {
  OccupancyMap m(0.01);
  m.insert(floor_with_a_block(), {}, kOrigin, 3.0);
  // The block's top (z = 0.1) over x, y in [0.1, 0.2]: as many voxels as the box counts.
  const Vec3 lo{0.05, 0.05, 0.09}, hi{0.25, 0.25, 0.11};
  bool more = true;
  const std::vector<Vec3> top = m.occupied(lo, hi, 100000, &more);
  EXPECT_FALSE(more);
  EXPECT_EQ(static_cast<int64_t>(top.size()), m.box(lo, hi).occupied);
  EXPECT_GT(top.size(), 80u);
  for (const Vec3& c : top) {
    EXPECT_EQ(m.state(c), Cell::Occupied);
    EXPECT_NEAR(c[2], 0.1, 0.011);
  }
  EXPECT_TRUE(std::is_sorted(top.begin(), top.end()));  // x, then y, then z: not the tree's walk
  const std::vector<Vec3> few = m.occupied(lo, hi, 10, &more);
  EXPECT_TRUE(more);
  EXPECT_EQ(few, std::vector<Vec3>(top.begin(), top.begin() + 10));
}

TEST(OccupancyMap, ARayWithoutAReturnClearsSpaceButMarksNothingOccupied) {
  OccupancyMap m(0.01);
  // Straight down, nothing seen within 0.5 m: a point beyond max_range along the ray.
  m.insert({}, {{0.0, 0.0, -5.0}}, kOrigin, 0.5);
  EXPECT_EQ(m.state({0.0, 0.0, 0.7}), Cell::Free);
  EXPECT_EQ(m.state({0.0, 0.0, 0.3}), Cell::Unknown);  // beyond the range
  EXPECT_EQ(m.box({-0.5, -0.5, -1.0}, {0.5, 0.5, 1.0}).occupied, 0);
}

TEST(OccupancyMap, SavedAndLoadedItIsTheSameMap) {
  OccupancyMap m(0.02);
  m.insert(floor_with_a_block(), {}, kOrigin, 3.0);
  const auto dir = std::filesystem::temp_directory_path() / ("sb_map_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "floor.bt").string();
  m.save(file);
  const OccupancyMap back = OccupancyMap::load(file);
  EXPECT_EQ(back.resolution(), 0.02);
  EXPECT_EQ(back.digest(), m.digest());
  EXPECT_EQ(back.leaves(), m.leaves());
  for (const Vec3& p : {Vec3{0, 0, 0.001}, Vec3{0, 0, 0.5}, Vec3{0.15, 0.15, 0.05}, Vec3{0.15, 0.15, 0.105}})
    EXPECT_EQ(back.state(p), m.state(p));
  EXPECT_THROW(OccupancyMap::load((dir / "none.bt").string()), std::runtime_error);
  std::filesystem::remove_all(dir);
}

TEST(OccupancyMap, TheSameCloudsGiveTheSameMapBitForBit) {
  OccupancyMap a(0.01), b(0.01);
  for (auto* m : {&a, &b}) m->insert(floor_with_a_block(), {}, kOrigin, 3.0);
  EXPECT_EQ(a.digest(), b.digest());
  b.insert({{0.25, -0.25, 0.3}}, {}, kOrigin, 3.0);
  EXPECT_NE(a.digest(), b.digest());
}

TEST(OccupancyMap, BadArgumentsAreRefusedSayingWhy) {
  EXPECT_THROW(OccupancyMap(0.0), std::invalid_argument);
  EXPECT_THROW(OccupancyMap(-1), std::invalid_argument);
  OccupancyMap m(0.01);
  try {
    m.box({0, 0, 0}, {10, 10, 10});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("at most 20000000 are looked at"), std::string::npos) << e.what();
  }
  EXPECT_THROW(m.box({1, 0, 0}, {0, 1, 1}), std::invalid_argument);
  EXPECT_THROW(m.free_area({0, 0, 0}, {1e6, 0, 0}), std::invalid_argument);  // beyond the map's range
  m.clear();
  EXPECT_EQ(m.leaves(), 0u);
}

namespace {
// free_spots as it was written first: one box() per centre (the footprint's column over
// the box's height), row by row. The reference for the column sums that replaced it.
std::vector<Vec3> free_spots_box_by_box(const OccupancyMap& m, const Vec3& lo, const Vec3& hi, double fx, double fy,
                                        double clearance, double max_unknown, size_t limit) {
  const double r = m.resolution(), hx = fx / 2 + clearance, hy = fy / 2 + clearance;
  const int nx = static_cast<int>(std::floor((hi[0] - lo[0] - 2 * hx) / r + 1e-9));
  const int ny = static_cast<int>(std::floor((hi[1] - lo[1] - 2 * hy) / r + 1e-9));
  std::vector<Vec3> out;
  for (int j = 0; j <= ny && out.size() < limit; ++j)
    for (int i = 0; i <= nx && out.size() < limit; ++i) {
      const double x = lo[0] + hx + i * r, y = lo[1] + hy + j * r;
      const BoxCounts c = m.box({x - hx, y - hy, lo[2]}, {x + hx, y + hy, hi[2]});
      const int64_t all = c.occupied + c.free + c.unknown;
      if (c.occupied == 0 && all > 0 && c.unknown <= max_unknown * all) out.push_back({x, y, lo[2]});
    }
  return out;
}

// The free area (and the whole area) of a box, asking box() for each column: a box one
// voxel wide at the voxel's centre (voxels lie on multiples of the resolution).
std::pair<double, double> free_area_column_by_column(const OccupancyMap& m, const Vec3& lo, const Vec3& hi) {
  const double r = m.resolution();
  const auto first = [&](double v) { return std::floor(v / r); };
  const int64_t nx = static_cast<int64_t>(first(hi[0]) - first(lo[0])) + 1;
  const int64_t ny = static_cast<int64_t>(first(hi[1]) - first(lo[1])) + 1;
  int64_t free_columns = 0;
  for (int64_t i = 0; i < nx; ++i)
    for (int64_t j = 0; j < ny; ++j) {
      const double x = (first(lo[0]) + i + 0.5) * r, y = (first(lo[1]) + j + 0.5) * r;
      const BoxCounts c = m.box({x, y, lo[2]}, {x, y, hi[2]});
      free_columns += c.occupied == 0 && c.unknown == 0;
    }
  return {free_columns * r * r, nx * ny * r * r};
}
}  // namespace

TEST(OccupancyMap, FreeSpotsAreWhatCountingEachFootprintsColumnGives) {
  // Maps of random clutter on the floor (seen from random points, so some space stays
  // unknown), every other one saved and loaded (the .bt file is of a pruned tree: leaves
  // coarser than a voxel), and random boxes, footprints, clearances and shares of unknown:
  // every spot, in order, as box by box.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int spots = 0, asked = 0;
  for (int map = 0; map < 6; ++map) {
    OccupancyMap m(map % 2 ? 0.01 : 0.02);
    auto hits = floor_with_a_block();
    for (int k = 0; k < 40; ++k)
      hits.push_back({-0.3 + 0.6 * u(rng), -0.3 + 0.6 * u(rng), 0.02 + 0.2 * u(rng)});
    m.insert(hits, {}, {0.4 * u(rng) - 0.2, 0.4 * u(rng) - 0.2, 0.6 + 0.6 * u(rng)}, 3.0);
    if (map % 2 == 0) {
      const auto file = std::filesystem::temp_directory_path() / ("free_spots_" + std::to_string(::getpid()) + ".bt");
      const size_t fine = m.leaves();
      m.save(file.string());
      m = OccupancyMap::load(file.string());
      std::filesystem::remove(file);
      ASSERT_LT(m.leaves(), fine);  // (pruned: some leaves span several voxels)
    }
    for (int q = 0; q < 40; ++q) {
      const Vec3 lo{-0.35 + 0.3 * u(rng), -0.35 + 0.3 * u(rng), -0.01 + 0.1 * u(rng)};
      const Vec3 hi{lo[0] + 0.05 + 0.4 * u(rng), lo[1] + 0.05 + 0.4 * u(rng), lo[2] + 0.01 + 0.2 * u(rng)};
      const double fx = 0.01 + 0.1 * u(rng), fy = 0.01 + 0.1 * u(rng), clearance = 0.02 * u(rng);
      const double max_unknown = q % 3 == 0 ? 0.0 : u(rng);
      const size_t limit = q % 4 == 0 ? 3 : 10000;
      const auto want = free_spots_box_by_box(m, lo, hi, fx, fy, clearance, max_unknown, limit);
      EXPECT_EQ(m.free_spots(lo, hi, fx, fy, clearance, max_unknown, limit), want)
          << "map " << map << " query " << q;
      spots += static_cast<int>(want.size());
      ++asked;
    }
  }
  EXPECT_GT(spots, asked);  // (the queries found spots, not only none)
}

TEST(OccupancyMap, TheFreeAreaIsWhatCountingEachColumnGives) {
  // free_area counts each column of the box from one walk; the reference asks box() for
  // each column. Random clutter, pruned maps too, random boxes.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int partly_free = 0;
  for (int map = 0; map < 4; ++map) {
    const double r = map % 2 ? 0.01 : 0.02;
    OccupancyMap m(r);
    auto hits = floor_with_a_block();
    for (int k = 0; k < 40; ++k) hits.push_back({-0.3 + 0.6 * u(rng), -0.3 + 0.6 * u(rng), 0.02 + 0.2 * u(rng)});
    m.insert(hits, {}, {0.4 * u(rng) - 0.2, 0.4 * u(rng) - 0.2, 0.6 + 0.6 * u(rng)}, 3.0);
    if (map >= 2) {
      const auto file = std::filesystem::temp_directory_path() / ("free_area_" + std::to_string(::getpid()) + ".bt");
      m.save(file.string());
      m = OccupancyMap::load(file.string());
      std::filesystem::remove(file);
    }
    for (int q = 0; q < 30; ++q) {
      const Vec3 lo{-0.35 + 0.3 * u(rng), -0.35 + 0.3 * u(rng), -0.01 + 0.1 * u(rng)};
      const Vec3 hi{lo[0] + 0.02 + 0.4 * u(rng), lo[1] + 0.02 + 0.4 * u(rng), lo[2] + 0.01 + 0.2 * u(rng)};
      const auto [want, want_area] = free_area_column_by_column(m, lo, hi);
      double area = 0;
      const double got = m.free_area(lo, hi, &area);
      EXPECT_NEAR(area, want_area, 1e-12) << "map " << map << " query " << q;
      EXPECT_NEAR(got, want, 1e-12) << "map " << map << " query " << q;
      partly_free += want > 0 && want < want_area;
    }
  }
  EXPECT_GT(partly_free, 10);  // (boxes neither all free nor all not)
}

TEST(OccupancyMap, FreeSpotsInALargeMappedBoxLookAtEachVoxelOnce) {
  // A 1 x 1 m floor seen from above, everything over it free: a 1 x 1 m x 10 cm box at
  // 1 cm holds 100,000 voxels, and 8,281 centres with a 10 cm footprint. Box by box that
  // was 8,281 walks over 1,000 voxels each, 55 times one box() of the whole box (and it
  // grows with the footprint's area: kMaxBoxVoxels did not bound it); the column sums walk
  // the box once. Compared with box() in the same process, the best of five each.
  OccupancyMap m(0.01);
  std::vector<Vec3> hits;
  for (double x = -0.5; x <= 0.5001; x += 0.005)
    for (double y = -0.5; y <= 0.5001; y += 0.005) hits.push_back({x, y, 0.0});
  m.insert(hits, {}, {0, 0, 1.5}, 3.0);
  const Vec3 lo{-0.5, -0.5, 0.02}, hi{0.5, 0.5, 0.12};
  const auto best_of_five = [](const auto& f) {
    double best = 1e9;
    for (int k = 0; k < 5; ++k) {
      const auto t0 = std::chrono::steady_clock::now();
      f();
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    return best;
  };
  std::vector<Vec3> spots;
  int64_t seen = 0;
  const double whole = best_of_five([&] { seen = m.box(lo, hi).free; });
  const double spotting = best_of_five([&] { spots = m.free_spots(lo, hi, 0.1, 0.1, 0.0, 0.2, 1'000'000); });
  EXPECT_GT(seen, 90'000);   // (the box is mapped: free, seen through)
  EXPECT_GT(spots.size(), 8'000u);  // (of 91 x 91 centres)
  // (in bands of rows here: the same spots as box by box, and the same free area)
  EXPECT_EQ(spots, free_spots_box_by_box(m, lo, hi, 0.1, 0.1, 0.0, 0.2, 1'000'000));
  double area = 0;
  const double free = m.free_area(lo, hi, &area);
  const auto [want, want_area] = free_area_column_by_column(m, lo, hi);
  EXPECT_NEAR(area, want_area, 1e-12);
  EXPECT_NEAR(free, want, 1e-12);
  EXPECT_GT(free, 0.8 * area);  // (the floor seen through: most columns free)
  EXPECT_LT(spotting, 5 * whole) << "free_spots " << spotting << " s, one box() of the whole box " << whole << " s";
}
