// Ticks a tree of N trivial always-succeeding C++ leaves under one Serial node (every
// tick restarts and ticks all N) and prints the microseconds per tick as JSON.
// Usage: tree_tick_bench N TICKS
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "tree/compound.hpp"
#include "tree/processor_registry.hpp"

using namespace skillbus::skills;

namespace {
class Succeed : public Node {
 public:
  Succeed() : Node("Succeed") {}

 protected:
  State step() override { return State::Success; }
};
}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 1000;
  const int ticks = argc > 2 ? std::atoi(argv[2]) : 2000;
  Children kids;
  for (int i = 0; i < n; ++i) kids.push_back(std::make_unique<Succeed>());
  CompoundNode root("Root", "", make_processor("Serial"), std::move(kids));
  for (int i = 0; i < 100; ++i) root.tick();  // warm up
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < ticks; ++i)
    if (root.tick() != State::Success) return 1;
  const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() / ticks;
  std::printf("{\"leaves\": %d, \"ticks\": %d, \"us_per_tick\": %.2f}\n", n, ticks, us);
  return 0;
}
