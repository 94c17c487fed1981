// The processors the tree engine knows, by name: a name-to-factory table (as
// BehaviorTree.CPP registers node types). It builds a processor from its spec
// ("Loop(3)", "NoFail(Selector)"), produces the "unknown processor" text from what it
// holds, and lists itself (the manager's `processors` RPC).
//
// Adding a processor: its header in processors/ and one line in processor_registry.cpp
// (docs/processors.md has a worked example).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "processor.hpp"

namespace skillbus::skills {

// What a processor may need from the node that owns it (set by the skill manager; a bare
// tree engine leaves it empty).
struct ProcessorHooks {
  // InferInvalid: refresh the owner's invalid parameters when a run starts; "" or why not.
  std::function<std::string()> before_run;
};

enum class ProcessorArg { None, Count, Processor };  // what goes between the parentheses

struct ProcessorInfo {
  std::string name;
  ProcessorArg arg = ProcessorArg::None;
  std::string summary;  // one line: what it does
};

class ProcessorRegistry {
 public:
  // spec: the text between the parentheses, parsed by `arg` (a Count: -1 when absent).
  struct Spec {
    int count = -1;
    std::unique_ptr<Processor> inner;  // ProcessorArg::Processor (SerialStar when absent)
  };
  using Factory = std::function<std::unique_ptr<Processor>(Spec, const ProcessorHooks&)>;

  void add(ProcessorInfo info, Factory make);
  // Registers P, built from nothing, a count or an inner processor (whatever P's constructor takes).
  template <class P>
  void add(ProcessorInfo info);

  // Throws std::invalid_argument naming the spec and listing what is known.
  std::unique_ptr<Processor> make(const std::string& spec, const ProcessorHooks& hooks = {}) const;
  std::vector<ProcessorInfo> list() const;  // in name order
  std::string known() const;                // "Loop(n), NoFail(processor), ..."

  // The standard table: every processor of processors/.
  static const ProcessorRegistry& standard();

 private:
  std::map<std::string, std::pair<ProcessorInfo, Factory>> table_;
};

template <class P>
void ProcessorRegistry::add(ProcessorInfo info) {
  add(std::move(info), [](Spec s, const ProcessorHooks& hooks) -> std::unique_ptr<Processor> {
    if constexpr (std::is_constructible_v<P, int, const ProcessorHooks&>) return std::make_unique<P>(s.count, hooks);
    else if constexpr (std::is_constructible_v<P, const ProcessorHooks&>) return std::make_unique<P>(hooks);
    else if constexpr (std::is_constructible_v<P, int>) return std::make_unique<P>(s.count);
    else if constexpr (std::is_constructible_v<P, std::unique_ptr<Processor>>) return std::make_unique<P>(std::move(s.inner));
    else return std::make_unique<P>();
  });
}

// ProcessorRegistry::standard().make(spec, hooks).
std::unique_ptr<Processor> make_processor(const std::string& spec, const ProcessorHooks& hooks = {});

}  // namespace skillbus::skills
