#include "manager.hpp"

#include <algorithm>
#include <cctype>

#include <sstream>
#include <stdexcept>

#include "liveness.hpp"
#include "skill_params.hpp"
#include "param_check.hpp"
#include "remote_primitive.hpp"
#include "skill_nodes.hpp"
#include "start_words.hpp"
#include "skillbus_msgs/skill_processors_t.hpp"
#include "skillbus_msgs/skill_state_t.hpp"
#include "tree/processor_registry.hpp"
#include "skillbus_msgs/skill_list_t.hpp"
#include "skillbus_msgs/skill_register_t.hpp"

namespace skillbus::skills {

using namespace skillbus_msgs;

namespace {

const char* kLog = "skill_mgr";

ParticipantConfig participant_config(const ManagerOptions& o) {
  ParticipantConfig c;
  c.name = o.name;
  c.kind = "skill_mgr";
  c.mode = o.wall_clock ? ClockMode::WallClock : ClockMode::Lockstep;
  c.wall_frame_period_ns = o.frame_period_ns;
  return c;
}

int8_t state_code(State s) { return static_cast<int8_t>(s); }  // State's values are skill_state_t's

}  // namespace

Manager::Manager(Bus& bus, ManagerOptions options)
    : bus_(bus),
      opt_(std::move(options)),
      participant_(bus, participant_config(opt_)),
      world_(bus, participant_, opt_.ontology_files, opt_.wall_clock),
      rpc_(bus, "SKILL") {
  if (!opt_.start_at_first_tick.empty()) {
    // "Type[:label] [KEY=VALUE ...]": values are typed at the start, by the description;
    // double quotes keep spaces in a value (Goal="(skiros:contain a b), (skiros:contain a c)").
    const std::vector<std::string> words = split_start_words(opt_.start_at_first_tick);
    const std::string head = words.empty() ? std::string() : words.front();
    skill_start_t req{};
    const auto colon = head.find(':');
    req.type = head.substr(0, colon);
    if (colon != std::string::npos) req.label = head.substr(colon + 1);
    for (size_t w = 1; w < words.size(); ++w) {
      const std::string& kv = words[w];
      const auto eq = kv.find('=');
      if (eq == std::string::npos || eq == 0)
        throw std::runtime_error("--start: '" + kv + "' is not KEY=VALUE");
      skillbus_msgs::skill_param_t p{};
      p.key = kv.substr(0, eq);
      skillbus_msgs::skill_value_t v{};
      v.type = skillbus_msgs::skill_value_t::STRING;
      v.s = kv.substr(eq + 1);
      p.values.push_back(v);
      p.num_values = 1;
      req.params.push_back(p);  // data_type empty: typed in begin()
    }
    req.num_params = static_cast<int32_t>(req.params.size());
    start_task_ = next_task_;
    starts_.push_back({next_task_++, req});
  }
  if (opt_.wall_clock) liveness_ = std::make_unique<Liveness>(bus_, registry_, opt_.name, opt_.liveness_timeout);
  directory_ = std::make_unique<Directory>(bus_, [this] {
    skillbus_msgs::skill_manager_info_t info{};
    info.robot = current_robot();
    info.name = opt_.name;
    info.agent = opt_.robot;
    if (info.agent.empty() && !opt_.robot_label.empty() && world_.ready())
      find_robot(world_.store(), opt_.robot_label, &info.agent);  // (stays "" when it is not there)
    // Which run of the manager this is, on both clocks: under lockstep too, so that a
    // watcher (the console) tells a new session's task 1 from the last one's. Identity
    // only, never behaviour: this announcement is outside the lockstep session.
    info.incarnation = liveness_ ? liveness_->incarnation() : run_id_;
    info.num_skills = static_cast<int32_t>(registry_.all().size());
    return info;
  });
  // RPC handlers only record requests: they can run while a tick waits for a skill
  // process, so they must not touch running trees.
  rpc_.add_method<skill_register_t, skill_register_t>("register", [this](const skill_register_t& reg) {
    // Bounded: every holder of the bus key may register, so names and numbers that would
    // grow the registry (and the announcement that lists it) without end are refused.
    auto name_ok = [](const std::string& n, size_t max) {
      if (n.empty() || n.size() > max) return false;
      for (char c : n)
        // (what a DDS topic takes, channel_bad_characters: one name works on both transports)
        if (!((std::isalnum(static_cast<unsigned char>(c)) && !(c & 0x80)) || c == '_')) return false;
      return true;
    };
    if (!name_ok(reg.process, 64) || !name_ok(reg.rpc_area, 64))
      throw RpcBadRequest("register: a process name and RPC area are 1 to 64 letters, digits or '_'");
    try {  // the manager calls the process there: a name that cannot be a channel is refused now
      rpc_request_channel(reg.rpc_area);
      rpc_reply_channel(reg.rpc_area);
    } catch (const std::invalid_argument& e) {
      throw RpcBadRequest("register: process " + reg.process + ": " + e.what());
    }
    const auto known = registry_.processes();
    if (std::find(known.begin(), known.end(), reg.process) == known.end() && known.size() >= kMaxProcesses)
      throw RpcError("register: " + std::to_string(kMaxProcesses) + " skill processes are registered already");
    if (reg.skills.size() > kMaxSkillsPerProcess)
      throw RpcBadRequest("register: at most " + std::to_string(kMaxSkillsPerProcess) + " skills per process");
    skill_register_t out = reg;
    if (liveness_) liveness_->registered(reg.process);
    out.errors = registry_.add(reg);
    out.num_errors = static_cast<int32_t>(out.errors.size());
    SB_INFO(kLog, "process " << reg.process << " registered " << reg.num_skills << " skill(s)"
                             << (out.errors.empty() ? "" : ", " + std::to_string(out.errors.size()) + " refused"));
    return out;
  });
  rpc_.add_method<skill_start_t, skill_processors_t>("processors", [](const skill_start_t&) {
    skill_processors_t out{};
    for (const auto& info : ProcessorRegistry::standard().list()) {
      out.names.push_back(info.name);
      out.args.push_back(info.arg == ProcessorArg::Count ? "n" : info.arg == ProcessorArg::Processor ? "processor" : "");
      out.summaries.push_back(info.summary);
    }
    out.num_processors = static_cast<int32_t>(out.names.size());
    return out;
  });
  rpc_.add_method<skill_start_t, skill_list_t>("list", [this](const skill_start_t&) {
    skill_list_t out{};
    for (const auto& [label, impl] : registry_.all()) {
      out.skills.push_back(impl.description);
      out.processes.push_back(impl.process);
    }
    out.num_skills = static_cast<int32_t>(out.skills.size());
    return out;
  });
  // tasks: the latest progress of one task (req.task > 0) or of all that are running, queued
  // or among the last finished (a watcher's catch-up: progress messages may be lost).
  rpc_.add_method<skill_start_t, skill_progress_list_t>("tasks", [this](const skill_start_t& req) {
    return tasks_reply(req.task);
  });
  rpc_.add_method<skill_start_t, skill_task_t>("start", [this](const skill_start_t& req) {
    const auto impls = registry_.find(req.type, req.label);
    if (impls.empty()) throw RpcError(unknown_skill_error(req.type, req.label));
    // Text values (KEY=VALUE from a command line) are parsed here by the description, and
    // keys and value types are checked, so a wrong one never starts; elements need the
    // world and are checked when the skill starts (the task then fails naming them).
    skill_start_t typed = req;
    for (auto& p : typed.params) {
      if (!p.data_type.empty()) continue;
      const std::string bad = parse_text(impls.front().description, p);
      if (!bad.empty()) throw RpcError(bad);
    }
    const std::string bad = check_given(impls.front().description, typed.params);
    if (!bad.empty()) throw RpcError(bad);
    skill_task_t out{};
    out.task = next_task_++;
    out.state = state_code(State::Idle);
    out.message = "queued";
    out.manager_incarnation = liveness_ ? liveness_->incarnation() : 0;
    starts_.push_back({out.task, typed});
    return out;
  });
  // pause / resume / step: a paused task is not ticked; step ticks it once. A queued task
  // (started, not begun) takes them too, and begins so.
  for (const char* verb : {"pause", "resume", "step"}) {
    const std::string v = verb;
    rpc_.add_method<skill_start_t, skill_task_t>(v, [this, v](const skill_start_t& req) {
      bool* paused = nullptr;
      bool* step_once = nullptr;
      bool queued = false;
      int8_t state = state_code(State::Idle);
      if (auto it = tasks_.find(req.task); it != tasks_.end()) {
        paused = &it->second->paused;
        step_once = &it->second->step_once;
        state = state_code(it->second->root->state());
      }
      for (auto& q : starts_)
        if (q.id == req.task) {
          paused = &q.paused;
          step_once = &q.step_once;
          queued = true;
        }
      if (!paused) throw RpcError("no running or queued task " + std::to_string(req.task));
      if (v == "pause") *paused = true;
      if (v == "resume") *paused = *step_once = false;
      if (v == "step") {
        if (!*paused) throw RpcError("task " + std::to_string(req.task) + " is not paused");
        *step_once = true;
      }
      skill_task_t out{};
      out.task = req.task;
      out.state = state;
      out.message = std::string(queued ? "queued, " : "") +
                    (*paused ? (*step_once ? "paused, stepping once" : "paused") : "running");
      return out;
    });
  }
  rpc_.add_method<skill_start_t, skill_task_t>("stop", [this](const skill_start_t& req) {
    auto it = tasks_.find(req.task);
    bool queued = false;
    for (const auto& q : starts_) queued |= q.id == req.task;
    if (it == tasks_.end() && !queued) throw RpcError("no running or queued task " + std::to_string(req.task));
    if (it != tasks_.end()) it->second->stop_requested = true;
    for (auto q = starts_.begin(); q != starts_.end(); ++q)
      if (q->id == req.task) {
        stopped_queued_.emplace_back(q->id, q->req.type);  // its end is published at the next frame
        starts_.erase(q);
        break;
      }
    skill_task_t out{};
    out.task = req.task;
    out.state = state_code(State::Running);
    out.message = "stopping";
    return out;
  });
}

RpcClient& Manager::client(const std::string& area) {
  auto& c = clients_[area];
  if (!c) {
    c = std::make_unique<RpcClient>(bus_, area, opt_.name);
    // A skill process may take seconds to answer (an expansion that plans): the manager
    // goes on announcing itself meanwhile, or the CLI would call it silent.
    if (liveness_) c->set_while_waiting([this] { liveness_->announce(); });
  }
  return *c;
}

void Manager::begin(const skill_start_t& req, int64_t id) {
  if (!world_.ready() && opt_.wall_clock && std::chrono::steady_clock::now() - last_world_try_ > std::chrono::seconds(5)) {
    // The world copy is loaded before a task starts (its element parameters are checked
    // and filled from it); with no world model server the task runs without one. First:
    // this pumps the bus, and what is heard meanwhile (a registration) may change the
    // skills looked up below.
    last_world_try_ = std::chrono::steady_clock::now();
    std::string why;
    world_.ensure(std::chrono::milliseconds(500), &why);
  }
  auto t = std::make_unique<Task>();
  t->id = id;
  t->type = req.type;
  t->label = req.label;
  auto impls = registry_.find(req.type, req.label);
  std::string bad;
  for (auto p : req.params) {  // a fresh blackboard per task; the user's values override static ones
    if (impls.empty()) break;
    if (p.data_type.empty() && bad.empty()) bad = parse_text(impls.front().description, p);  // --start KEY=VALUE
    if (bad.empty()) bad = check_given(impls.front().description, {p});
    t->blackboard.give(p.key, p);
  }
  t->ctx = std::unique_ptr<TaskContext>(new TaskContext{registry_, t->blackboard,
                                                        [this](const std::string& a) -> RpcClient& { return client(a); },
                                                        opt_.tick_timeout, (id << 32) + 1, &world_, opt_.robot,
                                                        opt_.robot_label});
  t->ctx->expand_timeout = opt_.expand_timeout;
  t->ctx->idle_ticks = &idle_ticks_;
  t->ctx->ticks_sent = &ticks_sent_;
  // (instance ids name running primitives in skill processes: unique across tasks)
  if (impls.empty() || !bad.empty()) {
    const std::string why = impls.empty() ? unknown_skill_error(req.type, req.label) : bad;
    SB_WARN(kLog, "task " << id << ": " << req.type << " cannot start: " << why);
    record_result(id, "Failure: " + why);
    publish_end_without_tree(id, req.type, why);
    return;
  }
  t->root = make_placeholder_node(*t->ctx, req.type, req.label, std::make_shared<Scope>());
  if (!t->root) {  // (cannot happen: nothing between the lookup and here pumps the bus)
    record_result(id, "Failure: " + unknown_skill_error(req.type, req.label));
    return;
  }
  SB_INFO(kLog, "task " << id << ": " << req.type << " (" << impls.front().description.label << ") started");
  tasks_[id] = std::move(t);
}

void Manager::tick(Task& t) {
  t.ctx->frame = frame_;
  t.ctx->sim_time_ns = sim_time_ns_;
  if (t.stop_requested) {
    t.root->preempt();
  } else {
    t.root->tick();
  }
  ++t.ticks;
}

void Manager::publish_progress(const Task& t) {
  skill_progress_t p{};
  p.task = t.id;
  p.state = state_code(t.root->state());
  p.tick = t.ticks;
  // The tree depth first, parents before children (built in place: every tick, every node).
  std::vector<std::pair<const Node*, int32_t>> todo{{t.root.get(), -1}};
  while (!todo.empty()) {
    const auto [n, parent] = todo.back();
    todo.pop_back();
    const int32_t me = static_cast<int32_t>(p.nodes.size());
    skill_node_progress_t& np = p.nodes.emplace_back();
    np.id = me;
    np.parent = parent;
    np.type = n->type();
    np.label = n->label();
    np.processor = n->processor_name();
    np.state = state_code(n->state());
    np.message = n->message();
    np.code = n->code();
    np.progress = n->progress();
    if (auto* prim = dynamic_cast<const RemotePrimitive*>(n)) np.params = prim->last_params_text();
    const auto& children = n->children();
    for (auto c = children.rbegin(); c != children.rend(); ++c) todo.emplace_back(c->get(), me);
  }
  p.num_nodes = static_cast<int32_t>(p.nodes.size());
  participant_.publish(progress_channel_, p);
  remember(std::move(p));  // (a task's whole tree, every tick: moved, not copied)
}

void Manager::publish_end_without_tree(int64_t id, const std::string& type, const std::string& message) {
  skill_progress_t p{};
  p.task = id;
  p.state = state_code(State::Failure);
  skill_node_progress_t root{};
  root.id = 0;
  root.parent = -1;
  root.type = type;
  root.state = p.state;
  root.message = message;
  root.code = skill_state_t::CODE_FAILED;
  p.nodes = {root};
  p.num_nodes = 1;
  participant_.publish(progress_channel_, p);
  remember(std::move(p));
}

void Manager::remember(skill_progress_t p) {
  const int64_t task = p.task;
  const bool now_finished = finished(static_cast<State>(p.state));
  auto it = latest_.find(task);
  const bool was_finished = it != latest_.end() && finished(static_cast<State>(it->second.state));
  latest_[task] = std::move(p);
  if (!now_finished || was_finished) return;
  finished_.push_back(task);
  while (finished_.size() > kFinishedKept) {
    latest_.erase(finished_.front());
    finished_.pop_front();
  }
}

skill_progress_list_t Manager::tasks_reply(int64_t task) const {
  skill_progress_list_t out{};
  auto wanted = [task](int64_t id) { return task <= 0 || id == task; };
  for (const auto& [id, p] : latest_)
    if (wanted(id)) out.tasks.push_back(p);
  // Begun tasks that have not ticked yet, and queued ones: one Idle node each.
  auto idle = [&out](int64_t id, const std::string& type, const std::string& label, const char* message) {
    skill_progress_t p{};
    p.task = id;
    p.state = static_cast<int8_t>(State::Idle);
    skill_node_progress_t root{};
    root.parent = -1;
    root.type = type;
    root.label = label;
    root.state = p.state;
    root.message = message;
    p.nodes = {root};
    p.num_nodes = 1;
    out.tasks.push_back(p);
  };
  for (const auto& [id, t] : tasks_)
    if (wanted(id) && !latest_.count(id)) idle(id, t->type, t->label, "started, not ticked yet");
  for (const auto& q : starts_)
    if (wanted(q.id)) idle(q.id, q.req.type, q.req.label, q.paused ? "queued, paused" : "queued");
  std::sort(out.tasks.begin(), out.tasks.end(), [](const auto& a, const auto& b) { return a.task < b.task; });
  if (task > 0 && out.tasks.empty())
    throw RpcError("no task " + std::to_string(task) + " (neither running, queued nor among the last " +
                   std::to_string(kFinishedKept) + " finished)");
  out.num_tasks = static_cast<int32_t>(out.tasks.size());
  return out;
}

void Manager::record_result(int64_t id, const std::string& result) {
  results_[id] = result;
  if (id == start_task_ && opt_.end_session_after_frames >= 0 && !opt_.wall_clock)
    participant_.request_end(opt_.end_session_after_frames, "task " + std::to_string(id) + " ended: " + result);
}

void Manager::end_if_finished(std::map<int64_t, std::unique_ptr<Task>>::iterator& it) {
  Task& t = *it->second;
  if (finished(t.root->state())) {
    SB_INFO(kLog, "task " << t.id << ": " << t.type << " " << to_string(t.root->state()) << ": " << t.root->message());
    record_result(t.id, std::string(to_string(t.root->state())) + ": " + t.root->message());
    it = tasks_.erase(it);
  } else {
    ++it;
  }
}

// Skills tick at sim times that are a whole number of tick periods: with frames that do not
// divide the period (30 ms frames, 40 ms ticks) they would tick only every 120 ms, silently.
// The clock's frames are known only from its first frames: the session fails, naming both.
void Manager::check_frame_period(int64_t frame, int64_t sim_time_ns) const {
  const int64_t period = sim_time_ns / frame;
  if (period > 0 && period * frame == sim_time_ns && opt_.tick_period_ns % period == 0) return;
  const double frame_ms = sim_time_ns / 1e6 / static_cast<double>(frame), tick_ms = opt_.tick_period_ns / 1e6;
  std::ostringstream why;
  why << "the clock's frames of " << frame_ms << " ms do not divide the skill manager's tick period of " << tick_ms
      << " ms (--tick-hz): skills would not tick at their rate; run frames that divide it";
  throw std::runtime_error(why.str());
}

void Manager::on_frame(int64_t frame, int64_t sim_time_ns) {
  if (frame == 0 && opt_.wall_clock && !world_.ready()) {
    // The world copy before the first task: its element parameters are checked and
    // filled from it (without a world model server skills run without one). Under
    // lockstep it is fetched when a task first needs it: a frame must not wait on a
    // server that may not be there (the master's ack timeout is short).
    std::string why;
    if (!world_.ensure(std::chrono::milliseconds(2000), &why)) SB_INFO(kLog, "no world model yet: " << why);
    last_world_try_ = std::chrono::steady_clock::now();
  }
  if (liveness_) liveness_->on_frame();
  if (!opt_.wall_clock && frame > 0 && frame_ <= 0) check_frame_period(frame, sim_time_ns);
  frame_ = frame;
  sim_time_ns_ = sim_time_ns;
  while (!stopped_queued_.empty()) {  // a task stopped before it began still ends visibly
    const auto [id, type] = stopped_queued_.front();
    stopped_queued_.pop_front();
    record_result(id, "Failure: stopped before it started");
    publish_end_without_tree(id, type, "stopped before it started");
  }
  if (sim_time_ns % opt_.tick_period_ns != 0) {
    // Between skill ticks only a stop is served: a stop reaches the skills (and the arm)
    // at the next frame, not up to a tick period later.
    for (auto it = tasks_.begin(); it != tasks_.end();) {
      if (!it->second->stop_requested) {
        ++it;
        continue;
      }
      tick(*it->second);
      publish_progress(*it->second);
      end_if_finished(it);
    }
    return;
  }
  while (!starts_.empty()) {
    // Queued until begun: begin() may pump the bus (the world copy, on the wall clock),
    // and a pause, step or stop heard meanwhile must still find the task.
    const int64_t id = starts_.front().id;
    const skill_start_t req = starts_.front().req;  // (a copy: a stop meanwhile erases the entry)
    begin(req, id);
    auto q = std::find_if(starts_.begin(), starts_.end(), [id](const QueuedStart& x) { return x.id == id; });
    auto it = tasks_.find(id);
    if (q == starts_.end()) {  // stopped while it began
      if (it != tasks_.end()) {
        tasks_.erase(it);  // (its end is published from stopped_queued_ at the next frame)
      } else {             // it could not begin: its end is published already, once is enough
        stopped_queued_.erase(std::remove_if(stopped_queued_.begin(), stopped_queued_.end(),
                                             [id](const auto& s) { return s.first == id; }),
                              stopped_queued_.end());
      }
      continue;
    }
    const QueuedStart flags = *q;
    starts_.erase(q);
    if (it != tasks_.end()) {
      it->second->paused = flags.paused;
      it->second->step_once = flags.step_once;
      // Paused before its first tick: watchers (the console, `skillbus watch`) hear of it
      // now, not at a tick that may be long in coming.
      if (flags.paused && !flags.step_once) publish_progress(*it->second);
    }
  }
  for (auto it = tasks_.begin(); it != tasks_.end();) {
    Task& t = *it->second;
    if (t.paused && !t.step_once && !t.stop_requested) {
      ++it;
      continue;
    }
    t.step_once = false;
    tick(t);
    publish_progress(t);
    end_if_finished(it);
  }
}

std::string Manager::unknown_skill_error(const std::string& type, const std::string& label) const {
  std::string avail;
  for (const auto& t : registry_.types()) avail += (avail.empty() ? "" : ", ") + t;
  std::string out = "unknown skill " + type + (label.empty() ? "" : " with label " + label) +
                    " (available: " + (avail.empty() ? std::string("none") : avail) + ")";
  const std::string gone = registry_.gone(type);
  return gone.empty() ? out : out + "; " + gone;
}

RunResult Manager::run_until(std::function<bool()> should_stop) {
  SB_INFO(kLog, "serving " << rpc_request_channel("SKILL") << " on " << bus_.url());
  participant_.on_frame = [this](int64_t f, int64_t t) { on_frame(f, t); };
  participant_.interrupted = should_stop;  // (also while it waits for a clock: LockstepParticipant)
  const RunResult r = participant_.run();
  // A lockstep session that ends in an error (a participant died) ends the tasks with it.
  for (auto& [id, t] : tasks_) {
    const std::string why = r.ok ? "the manager stopped" : r.error;
    SB_ERROR(kLog, "task " << id << ": " << t->type << " Failure: " << why);
    results_[id] = "Failure: " + why;
  }
  tasks_.clear();
  return r;
}

}  // namespace skillbus::skills
