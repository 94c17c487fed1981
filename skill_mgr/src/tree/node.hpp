// A node of a running skill tree: a primitive (leaf) or a compound skill whose children
// a processor ticks. The lifecycle is SkiROS2's:
//
//   tick() on an Idle node      start(); then one step (leaf: execute, compound: processor)
//   tick() on a Running node    one step
//   tick() on a finished node   reset(), then as on an Idle node (a restart)
//   preempt() on a Running node the node's preempt hook decides the result; then end
//   a step that ends the node   end() runs once
//
// Each node keeps the state, message, code and progress of its last step; observers
// (progress publishing) read them after a tick without the tree knowing.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "state.hpp"

namespace skillbus::skills {

class Node {
 public:
  explicit Node(std::string type, std::string label = "") : type_(std::move(type)), label_(std::move(label)) {}
  virtual ~Node() = default;
  Node(const Node&) = delete;
  Node& operator=(const Node&) = delete;

  State tick();
  void preempt();
  void reset();  // back to Idle, with the memory of processors cleared

  State state() const { return state_; }
  const std::string& type() const { return type_; }
  const std::string& label() const { return label_; }
  const std::string& message() const { return message_; }
  int code() const { return code_; }
  double progress() const { return progress_; }
  virtual const std::vector<std::unique_ptr<Node>>& children() const;
  virtual std::string processor_name() const { return ""; }
  // The name a parent's message gives it: its skill type, or for an anonymous group its
  // processor in parentheses, "(RetryOnFail(1))", as the progress tree shows it.
  std::string display_name() const { return type_.empty() ? "(" + processor_name() + ")" : type_; }

 protected:
  // Hooks. start: false fails the node (message says why). step: one tick's work.
  // on_preempt: the result of being preempted (default: Failure, "preempted"). finish:
  // after the last step. on_reset: forget per-run state.
  virtual bool start() { return true; }
  virtual State step() = 0;
  virtual State on_preempt();
  virtual void finish() {}
  virtual void on_reset() {}
  void set_result(const std::string& message, int code = 0, double progress = -1);

 private:
  std::string type_, label_;
  State state_ = State::Idle;
  std::string message_;
  int code_ = 0;
  double progress_ = 0;
};

}  // namespace skillbus::skills
