#include "manager.hpp"

#include <sstream>

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

int8_t state_code(State s) { return static_cast<int8_t>(s); }

}  // namespace

Manager::Manager(Bus& bus, ManagerOptions options)
    : bus_(bus),
      opt_(std::move(options)),
      participant_(bus, participant_config(opt_)),
      world_(bus, participant_, opt_.ontology_files, opt_.wall_clock),
      rpc_(bus, "SKILL") {
  if (!opt_.start_at_first_tick.empty()) {
    // "Type[:label] [KEY=VALUE ...]": values are typed at the start, by the description.
    std::istringstream words(opt_.start_at_first_tick);
    std::string head, kv;
    words >> head;
    skill_start_t req{};
    const auto colon = head.find(':');
    req.type = head.substr(0, colon);
    if (colon != std::string::npos) req.label = head.substr(colon + 1);
    while (words >> kv) {
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
    starts_.emplace_back(next_task_++, req);
  }
  // RPC handlers only record requests: they can run while a tick waits for a skill
  // process, so they must not touch running trees.
  rpc_.add_method<skill_register_t, skill_register_t>("register", [this](const skill_register_t& reg) {
    skill_register_t out = reg;
    out.errors = registry_.add(reg);
    out.num_errors = static_cast<int32_t>(out.errors.size());
    SB_INFO(kLog, "process " << reg.process << " registered " << reg.num_skills << " skill(s)"
                             << (out.errors.empty() ? "" : ", " + std::to_string(out.errors.size()) + " refused"));
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
  rpc_.add_method<skill_start_t, skill_task_t>("start", [this](const skill_start_t& req) {
    if (registry_.find(req.type, req.label).empty())
      throw RpcError("unknown skill " + req.type + (req.label.empty() ? "" : " with label " + req.label) +
                     " (available: " + [this] {
                       std::string s;
                       for (const auto& t : registry_.types()) s += (s.empty() ? "" : ", ") + t;
                       return s.empty() ? std::string("none") : s;
                     }() + ")");
    skill_task_t out{};
    out.task = next_task_++;
    out.state = state_code(State::Idle);
    out.message = "queued";
    starts_.emplace_back(out.task, req);
    return out;
  });
  // pause / resume / step: a paused task is not ticked; step ticks it once.
  for (const char* verb : {"pause", "resume", "step"}) {
    const std::string v = verb;
    rpc_.add_method<skill_start_t, skill_task_t>(v, [this, v](const skill_start_t& req) {
      auto it = tasks_.find(req.task);
      if (it == tasks_.end()) throw RpcError("no running task " + std::to_string(req.task));
      Task& t = *it->second;
      if (v == "pause") t.paused = true;
      if (v == "resume") t.paused = false;
      if (v == "step") {
        if (!t.paused) throw RpcError("task " + std::to_string(req.task) + " is not paused");
        t.step_once = true;
      }
      skill_task_t out{};
      out.task = req.task;
      out.state = state_code(t.root->state());
      out.message = t.paused ? (t.step_once ? "paused, stepping once" : "paused") : "running";
      return out;
    });
  }
  rpc_.add_method<skill_start_t, skill_task_t>("stop", [this](const skill_start_t& req) {
    auto it = tasks_.find(req.task);
    bool queued = false;
    for (auto& [id, r] : starts_) queued |= id == req.task;
    if (it == tasks_.end() && !queued) throw RpcError("no running task " + std::to_string(req.task));
    if (it != tasks_.end()) it->second->stop_requested = true;
    for (auto q = starts_.begin(); q != starts_.end(); ++q)
      if (q->first == req.task) {
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
  if (!c) c = std::make_unique<RpcClient>(bus_, area, opt_.name);
  return *c;
}

namespace {
// A parameter given as text (--start KEY=VALUE), typed by the skill's description.
void type_from_text(const skillbus_msgs::skill_description_t& d, skillbus_msgs::skill_param_t& p) {
  const std::string text = p.values.empty() ? "" : p.values[0].s;
  for (const auto& decl : d.params) {
    if (decl.key != p.key) continue;
    p.data_type = decl.data_type;
    p.concept = decl.concept;
    skillbus_msgs::skill_value_t v{};
    try {
      if (decl.data_type == "element") {
        v.type = skillbus_msgs::skill_value_t::ELEMENT;
        v.element.id = text;
        v.element.type = decl.concept;
      } else if (decl.data_type == "float") {
        v.type = skillbus_msgs::skill_value_t::FLOAT;
        v.f = std::stod(text);
      } else if (decl.data_type == "int") {
        v.type = skillbus_msgs::skill_value_t::INT;
        v.i = std::stoll(text);
      } else if (decl.data_type == "bool") {
        v.type = skillbus_msgs::skill_value_t::BOOL;
        v.b = text == "true" || text == "1" || text == "yes";
      } else {
        v.type = skillbus_msgs::skill_value_t::STRING;
        v.s = text;
      }
    } catch (const std::exception&) {
      SB_WARN("skill_mgr", "--start " << p.key << "=" << text << ": not a " << decl.data_type << "; ignored");
      p.values.clear();
      p.num_values = 0;
      return;
    }
    p.values = {v};
    p.num_values = 1;
    return;
  }
  SB_WARN("skill_mgr", "--start: " << d.type << " has no parameter " << p.key << "; ignored");
}
}  // namespace

void Manager::begin(const skill_start_t& req, int64_t id) {
  auto t = std::make_unique<Task>();
  t->id = id;
  t->type = req.type;
  t->label = req.label;
  auto impls = registry_.find(req.type, req.label);
  for (auto p : req.params) {  // a fresh blackboard per task
    if (p.data_type.empty() && !impls.empty()) type_from_text(impls.front()->description, p);
    t->blackboard.set(p.key, p);
  }
  t->ctx = std::unique_ptr<TaskContext>(new TaskContext{registry_, t->blackboard,
                                                        [this](const std::string& a) -> RpcClient& { return client(a); },
                                                        opt_.tick_timeout, (id << 32) + 1, &world_, opt_.robot});
  // (instance ids name running primitives in skill processes: unique across tasks)
  if (impls.empty()) {
    SB_WARN(kLog, "task " << id << ": skill " << req.type << " is not available");
    results_[id] = "Failure: skill " + req.type + " is not available";
    return;
  }
  if (impls.size() > 1 && req.label.empty()) {  // by type only: the first implementation that can start
    std::vector<Implementation> copies;
    for (const auto* x : impls) copies.push_back(*x);
    t->root = std::make_unique<Alternatives>(*t->ctx, std::move(copies), std::make_shared<Scope>());
  } else {
    t->root = make_skill_node(*t->ctx, *impls.front(), std::make_shared<Scope>());
  }
  SB_INFO(kLog, "task " << id << ": " << req.type << " (" << impls.front()->description.label << ") started");
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
  std::function<void(const Node&, int32_t)> walk = [&](const Node& n, int32_t parent) {
    skill_node_progress_t np{};
    np.id = static_cast<int32_t>(p.nodes.size());
    np.parent = parent;
    np.type = n.type();
    np.label = n.label();
    np.processor = n.processor_name();
    np.state = state_code(n.state());
    np.message = n.message();
    np.code = n.code();
    np.progress = n.progress();
    if (auto* prim = dynamic_cast<const RemotePrimitive*>(&n)) np.params = params_text(prim->last_params());
    p.nodes.push_back(np);
    const int32_t me = np.id;
    for (const auto& c : n.children()) walk(*c, me);
  };
  walk(*t.root, -1);
  p.num_nodes = static_cast<int32_t>(p.nodes.size());
  participant_.publish(channel("SB_SKILL_PROGRESS"), p);
}

void Manager::on_frame(int64_t frame, int64_t sim_time_ns) {
  if (sim_time_ns % opt_.tick_period_ns != 0) return;  // skills tick at 25 Hz of (sim) time
  frame_ = frame;
  sim_time_ns_ = sim_time_ns;
  while (!starts_.empty()) {
    auto [id, req] = starts_.front();
    starts_.pop_front();
    begin(req, id);
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
    if (finished(t.root->state())) {
      SB_INFO(kLog, "task " << t.id << ": " << t.type << " " << to_string(t.root->state()) << ": " << t.root->message());
      results_[t.id] = std::string(to_string(t.root->state())) + ": " + t.root->message();
      it = tasks_.erase(it);
    } else {
      ++it;
    }
  }
}

RunResult Manager::run_until(std::function<bool()> should_stop) {
  SB_INFO(kLog, "serving " << rpc_request_channel("SKILL") << " on " << bus_.url());
  participant_.on_frame = [this, should_stop](int64_t f, int64_t t) {
    on_frame(f, t);
    if (should_stop()) participant_.stop();
  };
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
