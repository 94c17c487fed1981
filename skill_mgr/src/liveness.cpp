#include "liveness.hpp"

#include <algorithm>

#include "skillbus/log.hpp"
#include "skillbus_msgs/skill_alive_t.hpp"

namespace skillbus::skills {

using skillbus_msgs::skill_alive_t;
using steady = std::chrono::steady_clock;

Liveness::Liveness(Bus& bus, Registry& registry, std::string manager_name, std::chrono::milliseconds timeout)
    : bus_(bus), registry_(registry), name_(std::move(manager_name)), timeout_(timeout), last_check_(steady::now()) {
  incarnation_ =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  subscription_ = bus_.subscribe(channel("SB_SKILL_HEARTBEAT"), [this](const std::string&, const uint8_t* data, size_t size) {
    skill_alive_t a;
    if (!decode_msg(data, size, a)) return;
    // A heartbeat of an unknown process or of an older run of it is not a registration.
    if (registry_.incarnation_of(a.sender) == a.incarnation) heard_from_[a.sender] = steady::now();
  });
}

void Liveness::registered(const std::string& process) { heard_from_[process] = steady::now(); }

void Liveness::on_frame() {
  announce();
  drop_silent();
}

void Liveness::announce() {
  const auto now = steady::now();
  if (now - last_announce_ < std::chrono::seconds(1)) return;
  last_announce_ = now;
  skill_alive_t a{};
  a.header.frame = -1;
  a.sender = name_;
  a.incarnation = incarnation_;
  a.processes = registry_.processes();
  a.num_processes = static_cast<int32_t>(a.processes.size());
  publish_msg(bus_, channel("SB_SKILL_MANAGER"), a);
}

void Liveness::drop_silent() {
  const auto now = steady::now();
  // The manager did not check for a while (stopped in a debugger or by a signal, starved
  // on a loaded machine, or at its start, waiting seconds for a world model while the
  // processes registered): the heartbeats sent meanwhile may still be on their way
  // through the transport (on DDS through Cyclone's own threads, which stopped with it
  // and deliver late joiners' history later, so caught_up_at below cannot tell), and
  // that time is not the processes' silence. A process that really stopped is still
  // dropped, that much later.
  if (now - last_check_ > timeout_ / 2) {
    const auto gap = now - last_check_;
    for (auto& entry : heard_from_) entry.second = std::min(entry.second + gap, now);
  }
  last_check_ = now;
  // Silent up to the last moment the manager had read everything that had come: after
  // the manager itself was not scheduled for seconds, the heartbeats wait in its socket
  // (a stopped manager dropped every process's skills when it went on).
  const auto heard_until = bus_.caught_up_at();
  for (const auto& process : registry_.processes()) {
    auto it = heard_from_.find(process);
    if (it == heard_from_.end()) {
      heard_from_[process] = now;  // registered before any heartbeat: count from now
      continue;
    }
    if (heard_until - it->second < timeout_) continue;
    const std::string why = "skill process " + process + " stopped answering (no heartbeat for " +
                            std::to_string(timeout_.count()) + " ms)";
    registry_.remove(process, why);
    heard_from_.erase(it);
    SB_WARN("skill_mgr", why << ": its skills are dropped until it registers again");
  }
}

}  // namespace skillbus::skills
