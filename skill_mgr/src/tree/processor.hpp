// A processor decides how a compound node ticks its children (SkiROS2's processors).
// One processor per file in processors/; processor_registry.hpp builds one from its name.
//
// process() is one tick of the parent: it ticks children (Node::tick restarts a finished
// child, so a processor that must not re-run a finished child does not tick it),
// preempts the ones that must stop, and returns the parent's state. reset() clears its
// memory (the node calls it on reset, after success, failure or preemption).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "node.hpp"

namespace skillbus::skills {

using Children = std::vector<std::unique_ptr<Node>>;

class Processor {
 public:
  virtual ~Processor() = default;
  virtual State process(const Children& children) = 0;
  virtual void reset() {}
  virtual std::string name() const = 0;
  // The node's message after process(): which child decided, and why.
  const std::string& message() const { return message_; }

 protected:
  void say(const std::string& m) { message_ = m; }
  static void preempt_from(const Children& children, size_t first);  // preempt children[first..] that run

 private:
  std::string message_;
};

}  // namespace skillbus::skills
