#include "processor.hpp"

#include <cctype>
#include <stdexcept>

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

void Processor::preempt_from(const Children& children, size_t first) {
  for (size_t i = first; i < children.size(); ++i) children[i]->preempt();
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

std::unique_ptr<Processor> make_processor(const std::string& spec_in) {
  const std::string spec = trim(spec_in);
  const auto open = spec.find('(');
  const std::string name = trim(spec.substr(0, open));
  std::string arg;
  if (open != std::string::npos) {
    if (spec.back() != ')') throw std::invalid_argument("processor '" + spec + "': missing ')'");
    arg = trim(spec.substr(open + 1, spec.size() - open - 2));
  }
  if (name == "Serial") return std::make_unique<Serial>();
  if (name == "SerialStar" || name == "Sequential") return std::make_unique<SerialStar>();
  if (name == "Selector") return std::make_unique<Selector>();
  if (name == "SelectorStar") return std::make_unique<SelectorStar>();
  if (name == "ParallelFf") return std::make_unique<ParallelFf>();
  if (name == "ParallelFs") return std::make_unique<ParallelFs>();
  if (name == "Loop") return std::make_unique<Loop>(count_arg(spec, arg));
  if (name == "RetryOnFail") return std::make_unique<RetryOnFail>(count_arg(spec, arg));
  if (name == "NoFail") return std::make_unique<NoFail>(make_processor(arg.empty() ? "SerialStar" : arg));
  throw std::invalid_argument("unknown processor '" + spec +
                              "' (Serial, SerialStar, Sequential, Selector, SelectorStar, ParallelFf, ParallelFs, "
                              "Loop(n), RetryOnFail(n), NoFail(processor))");
}

}  // namespace skillbus::skills
