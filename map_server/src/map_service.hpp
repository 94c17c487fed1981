// Private to map_server: the occupancy map as a service. It inserts every complete cloud
// on SB_CAMERA_CLOUD (or the named cameras') and answers the RPC area MAP. Under lockstep
// clouds come in canonical order within frames, and a query asked "as of frame n" is
// answered only once this server has finished its frame n: the same answer every run.
#pragma once

#include <map>
#include <set>
#include <string>

#include "cloud_input.hpp"
#include "skillbus/bus.hpp"
#include "skillbus/log.hpp"
#include "skillbus/map/occupancy_map.hpp"
#include "skillbus/rpc.hpp"
#include "skillbus_msgs/map_query_t.hpp"
#include "skillbus_msgs/map_reply_t.hpp"

namespace skillbus::map {

struct ServiceOptions {
  double resolution = 0.01;
  std::string maps_dir = ".";           // where save and load find maps by name
  std::set<std::string> cameras;        // empty: every camera
};

class MapService {
 public:
  MapService(Bus& bus, ServiceOptions options);
  void on_cloud_part(const uint8_t* data, size_t size, const std::string& ch);
  // Lockstep: the last frame this server finished (-1: none yet, or the wall clock).
  void set_completed_frame(int64_t frame) { completed_ = frame; }
  void set_lockstep(bool on) { lockstep_ = on; }
  RpcServer& rpc() { return rpc_; }
  void load(const std::string& name);  // throws std::runtime_error / std::invalid_argument
  const OccupancyMap& map() const { return map_; }
  int64_t clouds() const { return clouds_; }
  const BadInputCounter& bad_input() const { return bad_; }

 private:
  skillbus_msgs::map_reply_t base_reply() const;
  void gate(const skillbus_msgs::map_query_t& q) const;  // RpcDefer until the frame asked for is done
  std::string file_of(const std::string& name) const;

  Bus& bus_;
  ServiceOptions opt_;
  OccupancyMap map_;
  CloudParts parts_;
  RpcServer rpc_;
  BadInputCounter bad_{"map_server"};
  int64_t completed_ = -1, clouds_ = 0;
  bool lockstep_ = false;
  std::map<std::string, int64_t> last_capture_;  // per camera: the last capture inserted
};

}  // namespace skillbus::map
