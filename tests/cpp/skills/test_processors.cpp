// Table-driven tests of every processor over scripted children.
//
// A scripted child plays one outcome per execute: 'R' running, 'S' success, 'F' failure
// (the last letter repeats). Its log records, per parent tick (separated by '|'):
// '<' started, the outcome letter of each execute, '!' preempted, '>' ended.
// A case ticks the parent until it ends (or `ticks` times), then optionally preempts it,
// and compares the parent's results per tick and every child's log.
#include <gtest/gtest.h>

#include "tree/compound.hpp"
#include "tree/processor_registry.hpp"
#include "tree/processors/invert.hpp"
#include "tree/processors/serial_star.hpp"

using namespace skillbus::skills;

namespace {

class ScriptedLeaf : public Node {
 public:
  ScriptedLeaf(std::string name, std::string script, std::string& log)
      : Node(std::move(name)), script_(std::move(script)), log_(log) {}

 protected:
  bool start() override {
    log_ += '<';
    return true;
  }
  State step() override {
    const char c = script_[std::min(pos_++, script_.size() - 1)];
    log_ += c;
    set_result(std::string("scripted ") + c);
    return c == 'S' ? State::Success : c == 'F' ? State::Failure : State::Running;
  }
  State on_preempt() override {
    log_ += '!';
    return Node::on_preempt();
  }
  void finish() override { log_ += '>'; }

 private:
  std::string script_;
  size_t pos_ = 0;  // the script goes on across restarts
  std::string& log_;
};

char letter(State s) { return s == State::Success ? 'S' : s == State::Failure ? 'F' : 'R'; }

struct Case {
  std::string name;
  std::string processor;
  std::vector<std::string> scripts;
  std::string parent;              // expected parent result per tick
  std::vector<std::string> logs;   // expected per child
  int ticks = 10;                  // at most
  bool preempt_after = false;      // preempt the parent after `ticks` ticks
};

void run(const Case& c) {
  SCOPED_TRACE(c.name + " [" + c.processor + "]");
  std::vector<std::string> logs(c.scripts.size());
  Children kids;
  for (size_t i = 0; i < c.scripts.size(); ++i)
    kids.push_back(std::make_unique<ScriptedLeaf>("c" + std::to_string(i), c.scripts[i], logs[i]));
  CompoundNode parent("Parent", "", make_processor(c.processor), std::move(kids));
  std::string results;
  for (int t = 0; t < c.ticks; ++t) {
    const State s = parent.tick();
    results += letter(s);
    for (auto& l : logs) l += '|';
    if (finished(s)) break;
  }
  if (c.preempt_after) {
    parent.preempt();
    results += letter(parent.state());
    for (auto& l : logs) l += '|';
  }
  EXPECT_EQ(results, c.parent);
  for (size_t i = 0; i < logs.size(); ++i) EXPECT_EQ(logs[i], c.logs[i]) << "child c" << i;
}

}  // namespace

// clang-format off
const Case kCases[] = {
  // Serial: restarts finished children every tick; stops at the first not succeeded.
  {"serial all succeed at once", "Serial", {"S", "S"}, "S", {"<S>|", "<S>|"}},
  {"serial restarts finished children", "Serial", {"S", "RRS"}, "RRS",
   {"<S>|<S>|<S>|", "<R|R|S>|"}},
  {"serial stops at a failure", "Serial", {"S", "F", "S"}, "F", {"<S>|", "<F>|", "|"}},
  {"serial preempts later running children", "Serial", {"SF", "R"}, "RF",
   {"<S>|<F>|", "<R|!>|"}},
  {"serial preempted", "Serial", {"S", "R"}, "RRF", {"<S>|<S>||", "<R|R|!>|"}, 2, true},
  // SerialStar: memory of succeeded children, cleared when it ends.
  {"serialstar does not rerun succeeded children", "SerialStar", {"S", "RRS"}, "RRS",
   {"<S>|||", "<R|R|S>|"}},
  {"serialstar fails at a failure", "SerialStar", {"S", "RF", "S"}, "RF", {"<S>||", "<R|F>|", "||"}},
  {"sequential is serialstar", "Sequential", {"S", "RS"}, "RS", {"<S>||", "<R|S>|"}},
  {"serialstar preempted", "SerialStar", {"S", "R"}, "RF", {"<S>||", "<R|!>|"}, 1, true},
  // Selector: first child not failing wins; failed children are retried every tick.
  {"selector first success", "Selector", {"F", "S", "S"}, "S", {"<F>|", "<S>|", "|"}},
  {"selector all fail", "Selector", {"F", "F"}, "F", {"<F>|", "<F>|"}},
  {"selector retries failed children each tick", "Selector", {"F", "RS"}, "RS",
   {"<F>|<F>|", "<R|S>|"}},
  {"selector preempts later running ones", "Selector", {"FS", "R"}, "RS",
   {"<F>|<S>|", "<R|!>|"}},
  // SelectorStar: failed children are not tried again.
  {"selectorstar remembers failures", "SelectorStar", {"F", "RS"}, "RS", {"<F>||", "<R|S>|"}},
  {"selectorstar all fail", "SelectorStar", {"F", "RF"}, "RF", {"<F>||", "<R|F>|"}},
  // ParallelFf: all every tick; success when all succeeded; first failure preempts all.
  {"parallelff all succeed", "ParallelFf", {"S", "RRS", "RS"}, "RRS",
   {"<S>|||", "<R|R|S>|", "<R|S>||"}},
  {"parallelff failure preempts the rest", "ParallelFf", {"RF", "R", "R"}, "RF",
   {"<R|F>|", "<R|!>|", "<R|!>|"}},
  // ParallelFs: the first child to end decides.
  {"parallelfs first success", "ParallelFs", {"RS", "R"}, "RS", {"<R|S>|", "<R|!>|"}},
  {"parallelfs first failure", "ParallelFs", {"R", "RF"}, "RF", {"<R|R!>|", "<R|F>|"}},
  // Loop: n rounds, each round on its own ticks; failure fails.
  {"loop two rounds", "Loop(2)", {"S", "S"}, "RS", {"<S>|<S>|", "<S>|<S>|"}},
  {"loop fails when a child fails", "Loop(3)", {"S", "SF"}, "RF", {"<S>|<S>|", "<S>|<F>|"}},
  {"loop forever", "Loop", {"S"}, "RRRR", {"<S>|<S>|<S>|<S>|"}, 4},
  {"loop of zero rounds runs nothing", "Loop(0)", {"S"}, "S", {"|"}},
  // RetryOnFail(n): start over after a failure, at most n more attempts.
  {"retry succeeds on the second attempt", "RetryOnFail(2)", {"S", "FS"}, "RS",
   {"<S>|<S>|", "<F>|<S>|"}},
  {"retry gives up", "RetryOnFail(1)", {"F"}, "RF", {"<F>|<F>|"}},
  {"retry remembers within an attempt", "RetryOnFail(1)", {"S", "RFS", "S"}, "RRS",
   {"<S>||<S>|", "<R|F>|<S>|", "||<S>|"}},
  // NoFail: a failure becomes success.
  {"nofail turns failure into success", "NoFail(Serial)", {"S", "F"}, "S", {"<S>|", "<F>|"}},
  {"nofail keeps running", "NoFail(SerialStar)", {"RS"}, "RS", {"<R|S>|"}},
  // Invert: success and failure swapped (the worked example of docs/processors.md).
  {"invert turns success into failure", "Invert", {"S", "RS"}, "RF", {"<S>||", "<R|S>|"}},
  {"invert turns failure into success", "Invert(Selector)", {"F", "F"}, "S", {"<F>|", "<F>|"}},
};
// clang-format on

TEST(Processors, TableOfOutcomeSequences) {
  for (const Case& c : kCases) run(c);
}

TEST(Processors, MemoryIsClearedWhenTheParentRestarts) {
  // A SerialStar that succeeded and is ticked again starts from its first child.
  std::string a, b;
  Children kids;
  kids.push_back(std::make_unique<ScriptedLeaf>("a", "S", a));
  kids.push_back(std::make_unique<ScriptedLeaf>("b", "S", b));
  CompoundNode star("Star", "", make_processor("SerialStar"), std::move(kids));
  EXPECT_EQ(star.tick(), State::Success);
  EXPECT_EQ(star.tick(), State::Success);
  EXPECT_EQ(a, "<S><S>");
  EXPECT_EQ(b, "<S><S>");
}

TEST(Processors, NestedTreesPropagate) {
  // Serial( Selector(F, S), SerialStar(RS) )
  std::string l1, l2, l3;
  Children sel, star, top;
  sel.push_back(std::make_unique<ScriptedLeaf>("f", "F", l1));
  sel.push_back(std::make_unique<ScriptedLeaf>("s", "S", l2));
  star.push_back(std::make_unique<ScriptedLeaf>("rs", "RS", l3));
  top.push_back(std::make_unique<CompoundNode>("Sel", "", make_processor("Selector"), std::move(sel)));
  top.push_back(std::make_unique<CompoundNode>("Star", "", make_processor("SerialStar"), std::move(star)));
  CompoundNode root("Root", "", make_processor("Serial"), std::move(top));
  EXPECT_EQ(root.tick(), State::Running);
  EXPECT_EQ(root.tick(), State::Success);
  EXPECT_EQ(l1, "<F><F>");  // Serial restarts the selector, which retries its first child
  EXPECT_EQ(l3, "<RS>");
}

TEST(Processors, TheRegistryListsEveryProcessorAndNamesTheUnknownFromItself) {
  const auto& r = ProcessorRegistry::standard();
  std::vector<std::string> names;
  for (const auto& info : r.list()) {
    names.push_back(info.name);
    EXPECT_FALSE(info.summary.empty()) << info.name;
    // every listed processor can be built from its name
    EXPECT_NO_THROW(r.make(info.name)) << info.name;
  }
  EXPECT_EQ(names, (std::vector<std::string>{"InferInvalid", "Invert", "Loop", "NoFail", "ParallelFf", "ParallelFs",
                                             "RetryOnFail", "Selector", "SelectorStar", "Sequential", "Serial",
                                             "SerialStar"}));
  try {
    r.make("Parallel");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "unknown processor 'Parallel' (known: " + r.known() + ")");
    EXPECT_NE(r.known().find("Loop(n)"), std::string::npos);
    EXPECT_NE(r.known().find("NoFail(processor)"), std::string::npos);
  }
  EXPECT_THROW(r.make("Serial(2)"), std::invalid_argument);  // takes no argument
}

TEST(Processors, OneRegistryLineAddsAProcessor) {
  ProcessorRegistry mine;  // a registry of one's own, as a test or a plug-in would make
  mine.add<SerialStar>({"SerialStar", ProcessorArg::None, "in sequence, with memory"});
  mine.add<Invert>({"Invert", ProcessorArg::Processor, "swap success and failure"});
  EXPECT_EQ(mine.make("Invert(Invert)")->name(), "Invert(Invert(SerialStar))");
  EXPECT_THROW(mine.make("Serial"), std::invalid_argument);  // only what it was given
}

TEST(Processors, InferInvalidAsksItsOwnerOncePerRun) {
  int asked = 0;
  ProcessorHooks hooks;
  hooks.before_run = [&asked] {
    ++asked;
    return asked == 2 ? std::string("InferInvalid: cannot ground parameter Object") : std::string();
  };
  std::string log;
  Children kids;
  kids.push_back(std::make_unique<ScriptedLeaf>("c0", "RS", log));
  CompoundNode node("Group", "", make_processor("InferInvalid", hooks), std::move(kids));
  EXPECT_EQ(node.tick(), State::Running);
  EXPECT_EQ(node.tick(), State::Success);
  EXPECT_EQ(asked, 1);  // once for the run, not per tick
  EXPECT_EQ(node.tick(), State::Failure);  // the next run asks again, and its error fails it
  EXPECT_EQ(node.message(), "InferInvalid: cannot ground parameter Object");
  EXPECT_EQ(asked, 2);
  std::string bare_log;
  Children one;
  one.push_back(std::make_unique<ScriptedLeaf>("c0", "S", bare_log));
  CompoundNode bare("Bare", "", make_processor("InferInvalid"), std::move(one));
  EXPECT_EQ(bare.tick(), State::Failure);  // no owner: nothing to infer, said so
  EXPECT_EQ(bare_log, "");                 // and its children never ran
}

TEST(Processors, FactoryNamesWhatItDoesNotKnow) {
  EXPECT_EQ(make_processor("Loop(3)")->name(), "Loop(3)");
  EXPECT_EQ(make_processor(" RetryOnFail ")->name(), "RetryOnFail");
  EXPECT_EQ(make_processor("NoFail(Selector)")->name(), "NoFail(Selector)");
  EXPECT_THROW(make_processor("Loop(x)"), std::invalid_argument);
  EXPECT_THROW(make_processor("Loop(3"), std::invalid_argument);
  try {
    make_processor("Parallel");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown processor 'Parallel'"), std::string::npos);
  }
}

// A leaf that fails with a message of its own each time: the cause first, then consequences.
class FailingLeaf : public Node {
 public:
  explicit FailingLeaf(std::vector<std::string> whys) : Node("leaf"), whys_(std::move(whys)) {}

 protected:
  State step() override {
    set_result(whys_[std::min(n_++, whys_.size() - 1)]);
    return State::Failure;
  }

 private:
  std::vector<std::string> whys_;
  size_t n_ = 0;
};

TEST(Processors, RetryOnFailThatGivesUpNamesTheFirstFailureBesideTheLast) {
  Children kids;
  kids.push_back(std::make_unique<FailingLeaf>(std::vector<std::string>{"process killed", "nothing gripped"}));
  CompoundNode retry("Retry", "", make_processor("RetryOnFail(1)"), std::move(kids));
  State s = State::Running;
  for (int i = 0; i < 5 && s == State::Running; ++i) s = retry.tick();
  ASSERT_EQ(s, State::Failure);
  const std::string why = retry.message();
  EXPECT_NE(why.find("gave up after 2 attempts"), std::string::npos) << why;
  EXPECT_NE(why.find("nothing gripped"), std::string::npos) << why;
  EXPECT_NE(why.find("the first: "), std::string::npos) << why;
  EXPECT_NE(why.find("process killed"), std::string::npos) << why;
}

TEST(Processors, RetryOnFailFailingTheSameWayEachTimeSaysItOnce) {
  Children kids;
  kids.push_back(std::make_unique<FailingLeaf>(std::vector<std::string>{"unreachable"}));
  CompoundNode retry("Retry", "", make_processor("RetryOnFail(2)"), std::move(kids));
  State s = State::Running;
  for (int i = 0; i < 5 && s == State::Running; ++i) s = retry.tick();
  ASSERT_EQ(s, State::Failure);
  const std::string why = retry.message();
  EXPECT_NE(why.find("gave up after 3 attempts"), std::string::npos) << why;
  EXPECT_EQ(why.find("the first: "), std::string::npos) << why;
}

TEST(Processors, AnAnonymousGroupIsNamedByItsProcessorInItsParentsMessage) {
  std::string log;
  Children inner, outer;
  inner.push_back(std::make_unique<ScriptedLeaf>("Leaf", "F", log));
  outer.push_back(std::make_unique<CompoundNode>("", "", make_processor("RetryOnFail(0)"), std::move(inner)));
  CompoundNode top("Top", "", make_processor("SerialStar"), std::move(outer));
  State s = State::Running;
  for (int i = 0; i < 5 && s == State::Running; ++i) s = top.tick();
  ASSERT_EQ(s, State::Failure);
  EXPECT_EQ(top.message().rfind("(RetryOnFail(0)) failed: ", 0), 0u) << top.message();
}

TEST(Processors, ASelectorThatFailsNamesItsLastChildsFailure) {
  // A task whose fallback failed must say why (a ClearTable ended with only "all children
  // failed" when the skill process died under its Pick).
  for (const char* processor : {"Selector", "SelectorStar"}) {
    Children kids;
    kids.push_back(std::make_unique<FailingLeaf>(std::vector<std::string>{"pre-condition Holding failed"}));
    kids.push_back(std::make_unique<FailingLeaf>(std::vector<std::string>{"skill process skills did not answer"}));
    CompoundNode sel("Sel", "", make_processor(processor), std::move(kids));
    State s = State::Running;
    for (int i = 0; i < 5 && s == State::Running; ++i) s = sel.tick();
    ASSERT_EQ(s, State::Failure) << processor;
    EXPECT_NE(sel.message().find("all children failed; the last: "), std::string::npos) << sel.message();
    EXPECT_NE(sel.message().find("skill process skills did not answer"), std::string::npos) << sel.message();
  }
}
