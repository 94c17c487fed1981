// The skills the manager knows: implementations (by label) announced by skill
// processes, grouped by type (the description), with the process that serves each.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "skillbus_msgs/skill_description_t.hpp"
#include "skillbus_msgs/skill_register_t.hpp"

namespace skillbus::skills {

struct Implementation {
  skillbus_msgs::skill_description_t description;
  std::string process;
  std::string rpc_area;
  int64_t incarnation = 0;  // which run of the process announced it
};

class Registry {
 public:
  // Takes a process's announcement (replacing what it announced before); returns what
  // was refused, each naming the skill and why: a label served by another process, or
  // parameters other than those the type's registered implementations declare (keys,
  // data types, concepts, kinds: as in SkiROS2, implementations share their type's
  // description; the manager checks a start against one of them and may run any).
  std::vector<std::string> add(const skillbus_msgs::skill_register_t& reg);
  // Implementations of a type, in label order; with a label, only that one. Copies, not
  // pointers into the registry: the manager pumps the bus inside a request (an RPC to
  // the world model), a registration heard meanwhile replaces the entries, and a pointer
  // held across it read freed memory (the fuzz run's crash after 781,200 messages).
  std::vector<Implementation> find(const std::string& type, const std::string& label = "") const;
  // The incarnation a process last announced (0: never): a running skill of an older one is lost.
  int64_t incarnation_of(const std::string& process) const;
  const std::map<std::string, Implementation>& all() const { return by_label_; }
  std::vector<std::string> types() const;
  // Forgets a process and its skills, remembering `why` for each skill type that went
  // with it (until a process registers that type again).
  void remove(const std::string& process, const std::string& why);
  // Why no process serves `type` any more ("" if none was dropped).
  std::string gone(const std::string& type) const;
  std::vector<std::string> processes() const;  // those that announced themselves, sorted

 private:
  std::map<std::string, int64_t> incarnations_;
  std::map<std::string, Implementation> by_label_;
  std::map<std::string, std::string> gone_;  // skill type -> why its process was dropped
};

}  // namespace skillbus::skills
