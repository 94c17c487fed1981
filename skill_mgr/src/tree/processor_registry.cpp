#include "processor_registry.hpp"

#include <cctype>
#include <stdexcept>

#include "processors/infer_invalid.hpp"
#include "processors/invert.hpp"
#include "processors/loop.hpp"
#include "processors/no_fail.hpp"
#include "processors/parallel_ff.hpp"
#include "processors/parallel_fs.hpp"
#include "processors/retry_on_fail.hpp"
#include "processors/selector.hpp"
#include "processors/selector_star.hpp"
#include "processors/serial.hpp"
#include "processors/serial_star.hpp"

namespace skillbus::skills {

const ProcessorRegistry& ProcessorRegistry::standard() {
  static const ProcessorRegistry r = [] {
    ProcessorRegistry t;
    using A = ProcessorArg;
    t.add<Serial>({"Serial", A::None, "ticks the children in order until all succeed; finished children run again on later ticks"});
    t.add<SerialStar>({"SerialStar", A::None, "like Serial, remembering which children succeeded (the default processor)"});
    t.add<SerialStar>({"Sequential", A::None, "SerialStar's deprecated name (SkiROS2)"});
    t.add<Selector>({"Selector", A::None, "ticks the children in order until one succeeds; fails when all fail"});
    t.add<SelectorStar>({"SelectorStar", A::None, "like Selector, remembering the children already tried"});
    t.add<ParallelFf>({"ParallelFf", A::None, "ticks all children every tick; succeeds when all succeed, fails at the first failure"});
    t.add<ParallelFs>({"ParallelFs", A::None, "ticks all children every tick; ends with the first child that ends"});
    t.add<Loop>({"Loop", A::Count, "runs the children in sequence n times (forever without n)"});
    t.add<RetryOnFail>({"RetryOnFail", A::Count, "runs the children in sequence; after a failure starts over, at most n times"});
    t.add<NoFail>({"NoFail", A::Processor, "the inner processor (SerialStar by default), with a failure turned into success"});
    t.add<Invert>({"Invert", A::Processor, "the inner processor (SerialStar by default), with success and failure swapped"});
    t.add<InferInvalid>({"InferInvalid", A::None, "when a run starts, grounds the compound's invalid parameters again; then SerialStar"});
    return t;
  }();
  return r;
}

void ProcessorRegistry::add(ProcessorInfo info, Factory make) {
  const std::string name = info.name;
  table_[name] = {std::move(info), std::move(make)};
}

std::vector<ProcessorInfo> ProcessorRegistry::list() const {
  std::vector<ProcessorInfo> out;
  for (const auto& [name, entry] : table_) out.push_back(entry.first);
  return out;
}

std::string ProcessorRegistry::known() const {
  std::string s;
  for (const auto& [name, entry] : table_) {
    const ProcessorArg a = entry.first.arg;
    s += (s.empty() ? "" : ", ") + name + (a == ProcessorArg::Count ? "(n)" : a == ProcessorArg::Processor ? "(processor)" : "");
  }
  return s;
}

namespace {

std::string trim(std::string s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
  size_t i = 0;
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  return s.substr(i);
}

int count_arg(const std::string& spec, const std::string& arg) {
  if (arg.empty()) return -1;  // unbounded
  size_t used = 0;
  int n = 0;
  try {
    n = std::stoi(arg, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != arg.size() || n < 0) throw std::invalid_argument("processor '" + spec + "': '" + arg + "' is not a count");
  return n;
}

}  // namespace

std::unique_ptr<Processor> ProcessorRegistry::make(const std::string& spec_in, const ProcessorHooks& hooks) const {
  const std::string spec = trim(spec_in);
  const auto open = spec.find('(');
  const std::string name = trim(spec.substr(0, open));
  std::string arg;
  if (open != std::string::npos) {
    if (spec.back() != ')') throw std::invalid_argument("processor '" + spec + "': missing ')'");
    arg = trim(spec.substr(open + 1, spec.size() - open - 2));
  }
  auto it = table_.find(name);
  if (it == table_.end()) throw std::invalid_argument("unknown processor '" + spec + "' (known: " + known() + ")");
  Spec s;
  switch (it->second.first.arg) {
    case ProcessorArg::None:
      if (!arg.empty()) throw std::invalid_argument("processor '" + spec + "': " + name + " takes no argument");
      break;
    case ProcessorArg::Count: s.count = count_arg(spec, arg); break;
    case ProcessorArg::Processor: s.inner = make(arg.empty() ? "SerialStar" : arg, hooks); break;
  }
  return it->second.second(std::move(s), hooks);
}

std::unique_ptr<Processor> make_processor(const std::string& spec, const ProcessorHooks& hooks) {
  return ProcessorRegistry::standard().make(spec, hooks);
}

}  // namespace skillbus::skills
