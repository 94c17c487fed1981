"""Watching tasks from the terminal: `skillbus watch` attaches to a task someone else
started, and the manager's SKILL.tasks gives any watcher the latest tree of a task
(running, queued or among the last finished), so lost progress never leaves a watcher
showing a state that is not the last."""

import json
import re
import sys

from conftest import last_json
from support.held_task import hold_task
from test_skills import LIBS, cli, start_system


def test_watch_attaches_to_a_task_started_elsewhere_and_prints_only_changes(sandbox):
    start_system(sandbox, "flow_skills")
    # Held as soon as it runs (40 ticks: 1.6 s), then resumed once the watcher is attached:
    # a watcher started after a `run --detach` could come after the whole task on a loaded
    # machine, and see no tick.
    holder = hold_task(sandbox, 1)
    rc, out, err = cli(sandbox, "run", "Wait", "-p", "Ticks=40", "--detach")
    assert rc == 0, err
    task = int(out.strip())
    assert task == 1, out  # (the system's first task: the one held)
    holder.wait_for("held", 60, stream="stdout")
    watch = sandbox.start("watch", [sys.executable, "-m", "skillbus.cli", "watch", str(task), "--timeout", "30"],
                          env={"PYTHONPATH": str(LIBS)})
    watch.wait_for("watching from tick", 30, stream="stdout")
    assert cli(sandbox, "resume", task)[0] == 0
    assert sandbox.wait(watch, 60) == 0, watch.stdout() + watch.stderr()
    out = watch.stdout()
    assert re.search(rf"task {task}: Wait, watching from tick \d+", out), out
    ticks = re.findall(r"Wait Running: tick (\d+)", out)
    # one line per change (each tick changes the message), never a whole tree again
    assert len(ticks) == len(set(ticks)) and len(ticks) >= 2, out
    assert out.strip().endswith(f"task {task}: Success: waited"), out

    # after its end the manager still knows its final tree: a late watcher sees the end
    rc, out, err = cli(sandbox, "watch", str(task), "--json")
    assert rc == 0 and last_json(out)["state"] == "Success" and last_json(out)["tree"][0]["message"] == "waited", out

    rc, out, err = cli(sandbox, "watch", "999")
    assert rc == 2 and "no task 999 (neither running, queued nor among the last 20 finished)" in err, err


def test_a_failed_task_is_watched_to_its_failure_with_exit_code_1(sandbox):
    start_system(sandbox, "flow_skills")
    rc, out, _ = cli(sandbox, "run", "Wait", "-p", "Ticks=100000", "--detach")
    task = int(out.strip())
    watch = sandbox.start("watch", [sys.executable, "-m", "skillbus.cli", "watch", str(task)],
                          env={"PYTHONPATH": str(LIBS)})
    watch.wait_for("Wait Running: tick", 20, stream="stdout")
    assert cli(sandbox, "stop", str(task))[0] == 0
    assert sandbox.wait(watch, 20) == 1, watch.stdout() + watch.stderr()
    assert re.search(rf"task {task}: Failure: .*preempted at tick \d+", watch.stdout()), watch.stdout()


def test_tasks_answers_queued_running_and_finished_trees(sandbox):
    """SKILL.tasks, asked by a program of its own (a stand-in for any client)."""
    start_system(sandbox, "flow_skills")
    rc, out, _ = cli(sandbox, "run", "Wait", "-p", "Ticks=100000", "--detach")
    running = int(out.strip())
    rc, out, _ = cli(sandbox, "run", "Wait", "-p", "Ticks=2", "--timeout", "20")
    assert rc == 0
    probe = sandbox.start("probe", [sys.executable, "-c", PROBE])
    assert sandbox.wait(probe, 20) == 0, probe.stderr()
    tasks = {t["task"]: t for t in json.loads(probe.stdout())}
    assert tasks[running]["state"] == 2 and tasks[running]["tick"] > 0  # Running, ticking
    assert tasks[running + 1]["state"] == 3 and tasks[running + 1]["message"] == "waited"  # Success, kept


PROBE = """
import json
from skillbus.bus import open_bus
from skillbus.rpc import RpcClient
from skillbus.msgs import skill_progress_list_t, skill_start_t
reply = RpcClient(open_bus(), "SKILL", "probe").call("tasks", skill_start_t(), skill_progress_list_t, timeout=5)
print(json.dumps([{"task": p.task, "state": p.state, "tick": p.tick, "message": p.nodes[0].message}
                  for p in reply.tasks]))
"""


def test_tree_shows_a_skill_expanded_before_it_runs_and_a_tasks_tree_now(sandbox):
    start_system(sandbox, "flow_skills")
    rc, out, err = cli(sandbox, "tree", "Chain")
    assert rc == 0, out + err
    # the compound's tree from its skill process, anonymous groups by their processor
    assert out.splitlines() == ["Chain [SerialStar]", "  Produce", "  Consume", "  Consume", "  Mode",
                                "  (Selector)", "    Fails", "    Consume"], out
    rc, dot, err = cli(sandbox, "tree", "Chain", "--dot")
    assert rc == 0 and dot.startswith('digraph "Chain" {') and "->" in dot, dot + err
    rc, out, err = cli(sandbox, "tree", "NoSuchSkill")
    assert rc == 2 and "unknown skill 'NoSuchSkill'" in err, err
    rc, out, err = cli(sandbox, "tree", "999")
    assert rc == 2 and "does not know task 999" in err, err
