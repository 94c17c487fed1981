"""Skills across processes: a skill manager (C++), skill processes (Python) and the CLI."""

import sys
import time
from pathlib import Path

from conftest import last_json
from skillbus.waiting import wait_until

LIBS = Path(__file__).resolve().parent / "skill_libs"


def mgr_binary():
    from skillbus import paths
    return paths.binary("skill_mgr")


def cli(sandbox, *args, timeout=60):
    p = sandbox.start(f"cli-{args[0]}-{len(sandbox.procs)}", [sys.executable, "-m", "skillbus.cli", *map(str, args)],
                      env={"PYTHONPATH": str(LIBS)})
    rc = sandbox.wait(p, timeout)
    return rc, p.stdout(), p.stderr()


def start_wm(sandbox, data, *args, scene=None):
    """A wall-clock world model server on `data`, loading `scene` (default: the demo's)
    when `data` is new."""
    from skillbus import paths
    scene = scene or paths.demo_scene().with_suffix("").with_suffix(".ttl")
    return sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", str(data), *map(str, args),
                                "--scene", str(scene)])


def start_system(sandbox, *libraries, name="proc1", world_model=False, timeout=30):
    """A wall-clock skill manager and a skill process serving `libraries` (from
    skill_libs/), with a world-model client when `world_model`; returns both once the
    process has registered."""
    mgr = sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    proc = sandbox.start(name, [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", name,
                                *[x for lib in libraries for x in ("--library", lib)],
                                *(["--world-model"] if world_model else [])], env={"PYTHONPATH": str(LIBS)})
    proc.wait_for("registered", timeout)
    return mgr, proc


def test_parameters_flow_through_a_compound(sandbox):
    start_system(sandbox, "flow_skills")
    rc, out, err = cli(sandbox, "run", "Chain", "--watch", "--verbose", "--timeout", "30")
    assert rc == 0, out + err
    assert "task 1: Success" in out
    # Produce wrote Object; Consume read it by remap; the second got the specified value;
    # Mode used its static value; the Selector fell back past Fails to a Consume.
    assert 'Log=["widget-7", "fixed", "mode=open", "widget-7"]' in out, out
    assert "Item=widget-7" in out and "Item=fixed" in out and "Mode=open" in out
    assert "Fails Failure: always fails (code -3)" in out


def test_skills_lists_descriptions_and_a_broken_skill_does_not_stop_the_rest(sandbox):
    mgr, proc = start_system(sandbox, "flow_skills", "broken_skills", "no_such_module")
    loaded = last_json(proc.stdout())
    assert "fine" in loaded["skills"] and "broken" not in loaded["skills"]
    assert any("broken_skills.broken" in e and "'Missing'" in e for e in loaded["errors"])
    assert any("library no_such_module: ModuleNotFoundError" in e for e in loaded["errors"])
    rc, out, _ = cli(sandbox, "skills")
    assert rc == 0
    assert "Chain (chain, compound, process proc1)" in out
    assert "    Mode: str, Required, = open" in out
    assert "Fine (fine, primitive, process proc1)" in out


def test_start_errors_name_the_problem(sandbox):
    start_system(sandbox, "flow_skills")
    rc, _, err = cli(sandbox, "run", "NoSuchSkill")
    assert rc == 2 and "unknown skill 'NoSuchSkill'" in err
    rc, out, _ = cli(sandbox, "run", "Consume", "--timeout", "20")  # Item is required
    assert rc == 1 and "missing parameter Item of Consume" in out
    rc, out, _ = cli(sandbox, "run", "Consume", "-p", "Item=apple", "--timeout", "20")
    assert rc == 0 and "consumed apple" in out
    rc, _, err = cli(sandbox, "run", "Produce", "-p", "Ticks=many")
    assert rc == 2 and "'many' is not a int" in err
    # An implementation's label with --label naming another: the label ran, --label ignored.
    rc, _, err = cli(sandbox, "run", "consume", "--label", "produce", "-p", "Item=apple")
    assert rc == 2 and "error: 'consume' is the label of an implementation of Consume, and --label 'produce' " \
                       "names another: give the type (Consume --label produce) or one label" in err, err
    rc, out, _ = cli(sandbox, "run", "consume", "--label", "consume", "-p", "Item=pear", "--timeout", "20")
    assert rc == 0 and "consumed pear" in out, out


def test_each_run_gets_a_fresh_blackboard(sandbox):
    start_system(sandbox, "flow_skills")
    for _ in range(2):  # the second run's Log starts empty again
        rc, out, _ = cli(sandbox, "run", "Chain", "--verbose", "--timeout", "30")
        assert rc == 0 and 'Log=["widget-7", "fixed", "mode=open", "widget-7"]' in out, out


def test_pause_step_resume_and_stop(sandbox):
    import re
    start_system(sandbox, "flow_skills")
    run = sandbox.start("run", [sys.executable, "-m", "skillbus.cli", "run", "Wait", "--watch", "--timeout", "60"])

    def last_tick():
        ticks = re.findall(r"Wait Running: tick (\d+)", run.stdout())
        return int(ticks[-1]) if ticks else 0

    wait_until(lambda: last_tick() >= 3, 20, "tick 3 of Wait", interval=0.02,
               diagnostic=lambda: run.stdout() + run.stderr())
    assert cli(sandbox, "pause", "1")[0] == 0
    # (the manager sent the last tick's progress before it answered; the run prints it
    # when it gets a core: the tick shown is the paused one once it holds for a while)
    def settled() -> bool:
        before = last_tick()
        time.sleep(0.5)
        return last_tick() == before

    wait_until(settled, 20, "the shown tick to settle after the pause")
    paused_at = last_tick()
    time.sleep(0.5)
    assert last_tick() == paused_at  # not ticked while paused
    rc, out, _ = cli(sandbox, "step", "1")
    assert rc == 0 and "stepping once" in out
    wait_until(lambda: last_tick() > paused_at, 20, "the step's tick", diagnostic=lambda: run.stdout())
    time.sleep(0.5)
    assert last_tick() == paused_at + 1  # one tick, and then paused again
    assert cli(sandbox, "resume", "1")[0] == 0
    wait_until(lambda: last_tick() > paused_at + 2, 20, "ticks after the resume", diagnostic=lambda: run.stdout())
    rc, out, _ = cli(sandbox, "stop", "1")
    assert rc == 0 and "stopping" in out
    assert sandbox.wait(run, 20) == 1
    assert re.search(r"Wait Failure: preempted at tick \d+", run.stdout())
    rc, _, err = cli(sandbox, "stop", "99")
    assert rc == 1 and "no running or queued task 99" in err


PAUSE_QUEUED = """
import json, sys, time
from skillbus.bus import open_bus
from skillbus.msgs import skill_param_t, skill_progress_list_t, skill_start_t, skill_task_t, skill_value_t
from skillbus.rpc import RpcClient, RpcError
from skillbus.waiting import wait_until
client = RpcClient(open_bus(), "SKILL", "queued")
ticks = skill_param_t()
ticks.key, value = "Ticks", skill_value_t()
value.type, value.s = skill_value_t.STRING, "3"  # text: typed by the manager
ticks.values, ticks.num_values = [value], 1
start = skill_start_t()
start.type, start.params, start.num_params = "Wait", [ticks], 1
req = skill_start_t()
def call(verb):
    try:
        return client.call(verb, req, skill_task_t, timeout=5).message
    except RpcError as e:
        return f"refused: {e}"
def progress():
    p = client.call("tasks", req, skill_progress_list_t, timeout=5).tasks[0]
    return {"tick": p.tick, "state": p.state, "message": p.nodes[0].message}
for attempt in range(5):  # at once: the task waits for the next tick time (2 Hz)
    req.task = wait_until(lambda: client.call("start", start, skill_task_t, timeout=2), 20, "the start",
                          retry_on=(RpcError,)).task
    out = {"pause": call("pause")}
    if out["pause"] != "paused":
        break
    call("stop")  # (it began, and ticked, between the two calls on a slow machine: again)
wait_until(lambda: progress()["message"] != "queued, paused", 10, "the task to begin", interval=0.05)
time.sleep(1.1)  # two tick times
out["paused"] = progress()
out["step"] = call("step")
wait_until(lambda: progress()["tick"] >= 1, 10, "the step's tick", interval=0.05)
time.sleep(1.1)
out["stepped"] = progress()
out["resume"] = call("resume")
wait_until(lambda: progress()["state"] >= 3, 10, "the end", interval=0.05)  # (Success or Failure)
out["ended"] = progress()
print(json.dumps(out), flush=True)
"""


def test_a_task_paused_before_it_begins_begins_paused(sandbox):
    # A started task waits for the next tick time; pause, step and resume said "no running
    # task" to it while stop took it, and a client holding a task had to retry.
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock", "--tick-hz", "2"])
    proc = sandbox.start("proc1", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "proc1",
                                   "--library", "flow_skills"], env={"PYTHONPATH": str(LIBS)})
    proc.wait_for("registered", 30)
    probe = sandbox.start("queued", [sys.executable, "-c", PAUSE_QUEUED], env={"PYTHONPATH": str(LIBS)})
    assert sandbox.wait(probe, 60) == 0, probe.stdout() + probe.stderr()
    out = last_json(probe.stdout())
    assert out["pause"] == "queued, paused", out
    assert (out["paused"]["tick"], out["paused"]["state"]) == (0, 1), out  # begun paused: Idle, never ticked
    assert out["step"] == "paused, stepping once", out
    assert out["stepped"]["tick"] == 1, out  # one tick, then paused again
    assert out["resume"] == "running", out
    assert out["ended"]["message"] == "waited" and out["ended"]["tick"] == 3, out


def test_a_dead_skill_process_fails_its_primitive_with_a_named_error(sandbox):
    mgr, proc = start_system(sandbox, "flow_skills")
    sandbox.kill(proc)
    sandbox.wait(proc, 10)
    t0 = time.monotonic()
    rc, out, _ = cli(sandbox, "run", "Consume", "-p", "Item=x", "--timeout", "20")
    assert rc == 1
    assert "skill process proc1 did not answer the tick of consume within 1.0 s" in out, out
    assert time.monotonic() - t0 < 10  # (the tick's 1.0 s, the CLI's start-up on a loaded machine; not the 20 s)
    # the supervisor restarts it; it registers again and the skill runs
    restarted = sandbox.start("proc1-again", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "proc1",
                                              "--library", "flow_skills"], env={"PYTHONPATH": str(LIBS)})
    restarted.wait_for("registered", 30)
    rc, out, _ = cli(sandbox, "run", "Consume", "-p", "Item=x", "--timeout", "20")
    assert rc == 0 and "consumed x" in out, out


def test_several_tasks_run_at_once(sandbox):
    start_system(sandbox, "flow_skills")
    runs = [sandbox.start(f"run{i}", [sys.executable, "-m", "skillbus.cli", "run", "Wait", "-p", f"Ticks={n}",
                                      "--timeout", "60"], env={"PYTHONPATH": str(LIBS)})
            for i, n in enumerate((40, 20))]
    for r in runs:
        assert sandbox.wait(r, 60) == 0, r.stdout() + r.stderr()
    outs = [r.stdout() for r in runs]
    ids = sorted(int(o.split("task ")[1].split(":")[0]) for o in outs)
    assert ids == [1, 2]  # two tasks, each with its own id and its own result
    assert all("Wait Success: waited" in o for o in outs)


REGISTER_LONG_AREA = """
import sys
from skillbus.bus import open_bus
from skillbus.msgs import skill_register_t
from skillbus.rpc import RpcClient, RpcError
reg = skill_register_t()
reg.process, reg.rpc_area = sys.argv[1], sys.argv[2]
try:
    RpcClient(open_bus(), "SKILL", "probe").call("register", reg, skill_register_t, timeout=10)
    print("registered")
except RpcError as e:
    print("refused:", e)
"""


def test_a_process_name_too_long_for_its_channel_is_refused_at_start_and_at_register(sandbox):
    # LCM ends channel names at 63 bytes: SB_SKPROC_<NAME>_REQ of a 50-letter name is 64.
    # Before, such a process registered, then every tick failed to publish.
    mgr = sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    name = "p" * 50
    proc = sandbox.start("long", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", name,
                                  "--library", "flow_skills"], env={"PYTHONPATH": str(LIBS)})
    rc = sandbox.wait(proc, 30)
    assert rc == 2, proc.stdout() + proc.stderr()
    assert f"channel name 'SB_SKPROC_{name.upper()}_REQ' is 64 bytes: LCM ends channel names at 63" in proc.stderr()
    assert "Traceback" not in proc.stderr()
    # A process written with another SDK reaches the manager: it refuses, naming why.
    for area, want in (("SKPROC_" + "P" * 50, "refused: register: process x: channel name 'SB_SKPROC_"),
                       ("SKPROC_" + "P" * 49, "registered")):
        probe = sandbox.start(f"probe-{len(area)}", [sys.executable, "-c", REGISTER_LONG_AREA, "x", area])
        assert sandbox.wait(probe, 30) == 0, probe.stderr()
        assert probe.stdout().startswith(want), probe.stdout()
    assert mgr.returncode is None  # (the manager goes on)


def test_a_process_name_a_dds_topic_refuses_is_refused_at_start(sandbox):
    # '-' and '.' ran on LCM and failed on DDS at the manager's first tick.
    for name in ("my-arm", "my.arm"):
        proc = sandbox.start(f"bad-{len(sandbox.procs)}", [sys.executable, "-m", "skillbus.cli", "skills-process",
                                                            "--name", name, "--library", "flow_skills"],
                             env={"PYTHONPATH": str(LIBS)})
        assert sandbox.wait(proc, 30) == 2, proc.stderr()
        assert f"error: --name '{name}': a skill process name is 1 to 64 letters, digits or '_'" in proc.stderr()


def test_a_process_the_policy_would_silence_is_refused_at_start(sandbox, tmp_path):
    # An added process signs as "operator" unless told otherwise; under deploy/policy.conf
    # only "skills" answers ticks. Before, it registered and every tick it answered was
    # dropped as forbidden ("did not answer the tick"); now it names the rule at start.
    from skillbus import paths
    policy = paths.REPO_ROOT / "deploy" / "policy.conf"
    env = {"PYTHONPATH": str(LIBS), "SKILLBUS_POLICY_FILE": str(policy), "SKILLBUS_IDENTITY": "operator"}
    proc = sandbox.start("added", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "added",
                                   "--library", "flow_skills"], env=env)
    assert sandbox.wait(proc, 30) == 2, proc.stderr()
    assert (f"error: skills-process added: the bus policy {policy} does not let 'operator' send on "
            "SB_SKPROC_ADDED_REP") in proc.stderr(), proc.stderr()
    env["SKILLBUS_IDENTITY"] = "skills"  # as the policy names skill processes
    ok = sandbox.start("added-ok", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "added",
                                    "--library", "flow_skills", "--standalone"], env=env)
    ok.wait_for("serving", 30)


DISCOVER = """
from skillbus.bus import open_bus
from skillbus.skill.managers import discover
print([m.incarnation for m in discover(open_bus(), 1.5)])
"""


def test_a_lockstep_manager_says_which_run_it_is(sandbox):
    # Under lockstep every manager announced incarnation 0: a watcher (the console) took a
    # second session's manager for the first, and its task 1 for the old, ended one.
    seen = []
    for run in range(2):
        mgr = sandbox.start(f"skill_mgr-{run}", [mgr_binary()])  # lockstep: waits for a clock master
        probe = sandbox.start(f"discover-{run}", [sys.executable, "-c", DISCOVER])
        assert sandbox.wait(probe, 30) == 0, probe.stderr()
        (incarnation,) = __import__("ast").literal_eval(probe.stdout().strip().splitlines()[-1])
        seen.append(incarnation)
        sandbox.kill(mgr)
        sandbox.wait(mgr, 10)
    assert 0 not in seen and seen[0] != seen[1], seen


def test_a_manager_with_no_skills_yet_says_so(sandbox):
    # Right after `skillbus launch` (it returns once every program runs) the skill process
    # may not have registered: "unknown skill 'ClearTable' (available: none)" read as if
    # the skill did not exist.
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    for command in (["run", "ClearTable", "--timeout", "10"], ["tree", "ClearTable"]):
        rc, _, err = cli(sandbox, *command)
        assert rc == 2 and "error: unknown skill 'ClearTable': the skill manager has no skills yet" in err, err
