#include "map_service.hpp"

#include <cmath>

#include "skillbus/files.hpp"

namespace skillbus::map {

using skillbus_msgs::map_query_t;
using skillbus_msgs::map_reply_t;

namespace {
constexpr const char* kLog = "map_server";
constexpr int32_t kMaxPoints = 100'000;  // a state query's points (a reply of 400 KB)
constexpr size_t kMaxVoxels = 200'000;  // an occupied query's voxels (a reply of 2.4 MB, in chunks)

Vec3 vec(const double (&a)[3]) { return {a[0], a[1], a[2]}; }

void check_finite(const map_query_t& q, bool points, bool box) {
  if (points) {
    if (q.num_points < 0 || q.num_points > kMaxPoints)
      throw RpcBadRequest("state: between 0 and " + std::to_string(kMaxPoints) + " points, not " +
                          std::to_string(q.num_points));
    for (const auto& p : q.points)
      for (double v : p)
        if (!std::isfinite(v)) throw RpcBadRequest("state: a point is not finite");
  }
  if (box)
    for (int i = 0; i < 3; ++i)
      if (!std::isfinite(q.box_min[i]) || !std::isfinite(q.box_max[i])) throw RpcBadRequest("the box is not finite");
}
}  // namespace

MapService::MapService(Bus& bus, ServiceOptions options)
    : bus_(bus), opt_(std::move(options)), map_(opt_.resolution), rpc_(bus, "MAP") {
  auto method = [this](const std::string& name, auto fn) {
    rpc_.add_method<map_query_t, map_reply_t>(name, [this, fn](const map_query_t& q) {
      gate(q);
      map_reply_t r = base_reply();
      fn(q, r);
      return r;
    });
  };
  method("info", [](const map_query_t&, map_reply_t&) {});
  method("state", [this](const map_query_t& q, map_reply_t& r) {
    check_finite(q, true, false);
    for (const auto& p : q.points) {
      const Cell c = map_.state({p[0], p[1], p[2]});
      int32_t state = map_reply_t::UNKNOWN;  // (the generated constants are of distinct unnamed enums)
      if (c == Cell::Free) state = map_reply_t::FREE;
      if (c == Cell::Occupied) state = map_reply_t::OCCUPIED;
      r.states.push_back(state);
    }
    r.num_states = static_cast<int32_t>(r.states.size());
  });
  method("box", [this](const map_query_t& q, map_reply_t& r) {
    check_finite(q, false, true);
    try {
      const BoxCounts c = map_.box(vec(q.box_min), vec(q.box_max));
      r.occupied = c.occupied;
      r.free = c.free;
      r.unknown = c.unknown;
    } catch (const std::invalid_argument& e) {
      throw RpcBadRequest(std::string("box: ") + e.what());
    }
  });
  method("occupied", [this](const map_query_t& q, map_reply_t& r) {
    check_finite(q, false, true);
    try {
      bool more = false;
      for (const Vec3& c : map_.occupied(vec(q.box_min), vec(q.box_max), kMaxVoxels, &more))
        r.voxels.push_back({static_cast<float>(c[0]), static_cast<float>(c[1]), static_cast<float>(c[2])});
      if (more)
        throw RpcBadRequest("occupied: more than " + std::to_string(kMaxVoxels) +
                            " occupied voxels in the box; ask for a smaller one");
    } catch (const std::invalid_argument& e) {
      throw RpcBadRequest(std::string("occupied: ") + e.what());
    }
    r.num_voxels = static_cast<int32_t>(r.voxels.size());
  });
  method("free_area", [this](const map_query_t& q, map_reply_t& r) {
    check_finite(q, false, true);
    try {
      r.free_area_m2 = map_.free_area(vec(q.box_min), vec(q.box_max), &r.area_m2);
    } catch (const std::invalid_argument& e) {
      throw RpcBadRequest(std::string("free_area: ") + e.what());
    }
  });
  method("free_spots", [this](const map_query_t& q, map_reply_t& r) {
    check_finite(q, false, true);
    try {
      for (const auto& s : map_.free_spots(vec(q.box_min), vec(q.box_max), q.footprint[0], q.footprint[1], q.clearance))
        r.spots.push_back({s[0], s[1], s[2]});
    } catch (const std::invalid_argument& e) {
      throw RpcBadRequest(std::string("free_spots: ") + e.what());
    }
    r.num_spots = static_cast<int32_t>(r.spots.size());
  });
  method("save", [this](const map_query_t& q, map_reply_t& r) {
    r.file = file_of(q.name);
    map_.save(r.file);
    SB_INFO(kLog, "saved the map (" << map_.leaves() << " leaves) to " << r.file);
  });
  method("load", [this](const map_query_t& q, map_reply_t& r) {
    load(q.name);
    const map_reply_t now = base_reply();
    r = now;
    r.file = file_of(q.name);
  });
  method("clear", [this](const map_query_t&, map_reply_t& r) {
    map_.clear();
    clouds_ = 0;
    last_capture_.clear();
    r = base_reply();
  });
}

std::string MapService::file_of(const std::string& name) const {
  try {
    return file_in(opt_.maps_dir, name, ".bt", "map name");
  } catch (const std::invalid_argument& e) {
    throw RpcBadRequest(e.what());
  }
}

void MapService::load(const std::string& name) {
  const std::string file = file_of(name);
  OccupancyMap m = OccupancyMap::load(file);  // (a map that cannot be read leaves the old one)
  map_ = std::move(m);
  clouds_ = 0;
  last_capture_.clear();
  SB_INFO(kLog, "loaded the map " << file << " (" << map_.leaves() << " leaves, resolution " << map_.resolution()
                                  << " m)");
}

void MapService::gate(const map_query_t& q) const {
  if (q.as_of_frame < -1) throw RpcBadRequest("as_of_frame must be -1 (now) or a frame");
  if (lockstep_ && q.as_of_frame > completed_) throw RpcDefer();
}

map_reply_t MapService::base_reply() const {
  map_reply_t r{};
  r.frame = lockstep_ ? completed_ : -1;
  r.resolution = map_.resolution();
  r.clouds = clouds_;
  r.leaves = static_cast<int64_t>(map_.leaves());
  for (const auto& [camera, capture] : last_capture_) {
    r.cameras.push_back(camera);
    r.captures.push_back(capture);
  }
  r.num_cameras = static_cast<int32_t>(r.cameras.size());
  return r;
}

void MapService::on_cloud_part(const uint8_t* data, size_t size, const std::string& ch) {
  skillbus_msgs::camera_cloud_t m;
  if (!decode_msg(data, size, m)) {
    bad_.record(ch, "does not decode as camera_cloud_t", size);
    return;
  }
  if (!opt_.cameras.empty() && !opt_.cameras.count(m.camera)) return;
  try {
    auto cloud = parts_.add(m, map_.resolution());
    if (!cloud) return;
    map_.insert(cloud->hits, cloud->misses, cloud->origin, cloud->far);
    ++clouds_;
    last_capture_[cloud->camera] = cloud->capture;
  } catch (const std::invalid_argument& e) {
    bad_.record(ch, e.what(), size);
  }
}

}  // namespace skillbus::map
