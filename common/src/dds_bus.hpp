// The Cyclone DDS backend of Bus: dds://DOMAIN[?peers=HOST,HOST&interface=ADDR&state=best-effort].
//
// Messages stay LCM-encoded; DDS carries each as octets (skillbus::Envelope,
// lcmtypes/dds/envelope.idl), one topic per channel, so a process receives only the
// channels it reads. Quality of service per channel class, the loopback-only default and
// the options: docs/transport.md ("DDS"). The Python twin is py_skills/skillbus/dds.py.
#pragma once

#include <dds/dds.h>

#include <map>
#include <string>
#include <vector>

#include "skillbus/bus.hpp"

namespace skillbus {

struct DdsUrl {
  int domain = 0;
  std::vector<std::string> peers;
  std::string interface = "127.0.0.1";
  bool state_best_effort = false;
};
// The parts of a dds:// URL; BusError naming what is wrong.
DdsUrl parse_dds_url(const std::string& url);
// Local by default (as udpm://): BusError when the interface or a peer is not this host,
// unless $SKILLBUS_NETWORK allows a network.
void check_dds_local(const DdsUrl& u, const std::string& url);
// Cyclone DDS's configuration for it: one interface, no multicast, discovery by unicast
// to localhost and the peers (the same as skillbus.dds.config_xml).
std::string dds_config_xml(const DdsUrl& u);

class DdsBus : public Bus {
 public:
  explicit DdsBus(const std::string& url);
  ~DdsBus() override;
  void publish(const std::string& channel, const void* data, size_t size) override;
  int subscribe(const std::string& channel, Handler handler, int queue_capacity = 10000) override;
  void unsubscribe(int subscription_id) override;
  bool handle(std::chrono::milliseconds timeout) override;
  std::string url() const override { return url_; }
  std::chrono::steady_clock::time_point caught_up_at() const override { return caught_up_; }
  // Messages not sent because a matched reader took none for the writer's blocking time
  // (a stopped process, or a killed one until its lease ends): lost, as on LCM.
  long lost_sends() const { return lost_sends_; }

 private:
  struct Reader {
    dds_entity_t reader = 0;
    dds_entity_t condition = 0;
    std::map<int, Handler> handlers;
    dds_time_t since = 0;  // the oldest source time delivered
  };
  dds_entity_t topic(const std::string& channel);
  dds_qos_t* qos(const std::string& channel) const;  // (the caller deletes it)
  bool take_one();

  std::string url_;
  std::chrono::steady_clock::time_point caught_up_ = std::chrono::steady_clock::now();  // nothing left to take
  DdsUrl parsed_;
  dds_entity_t participant_ = 0;
  dds_entity_t waitset_ = 0;
  std::map<std::string, dds_entity_t> topics_, writers_;
  std::map<std::string, Reader> readers_;
  std::vector<std::string> order_;  // channels read, in a rotating order: none starves
  std::map<int, std::string> subs_;
  int next_id_ = 1;
  long handler_failures_ = 0;  // logged rate-limited
  long lost_sends_ = 0;
};

}  // namespace skillbus
