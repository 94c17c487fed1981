"""The demo's live view loses no progress: `skillbus demo` (the whole pick-and-place
system under supervisord, lockstep) shows the running skill up to the end of the task,
and the skill tree it prints at the end is the task's final progress. The truth is the
demo's own LCM log (skillbus record, every message of the run)."""

import re
import signal
import sys

import lcm

from skillbus import auth
from skillbus.msgs import decode, skill_progress_t
from skillbus.skill import State
from support.held_task import hold_task
from test_launch_run_dir import box, netns_procs  # noqa: F401 (box: a fixture)

LIVE = re.compile(r"^  t=\s*(\d+\.\d+) s  (.*)$", re.M)


def logged_progress(path):
    out = []
    for ev in lcm.EventLog(str(path), "r"):
        if ev.channel.endswith("SB_SKILL_PROGRESS"):
            p = decode(skill_progress_t, auth.strip(ev.data))  # (the log keeps the wire's authenticators)
            if p is not None and p.task == 1:
                out.append(p)
    return out


def test_the_live_view_follows_the_task_to_its_end(box, tmp_path):  # noqa: F811
    run_dir = tmp_path / "demo"
    for i in range(2):  # two cores kept busy (as on a shared machine): the view must keep up anyway
        box.start(f"busy{i}", [sys.executable, "-c", "while True: pass"])
    demo = box.start("demo", [sys.executable, "-m", "skillbus.cli", "demo", "--run-dir", str(run_dir)],
                     env={"SKILLBUS_NETNS": "1"})  # (the sandbox is the demo's network namespace)
    rc = box.wait(demo, 240)
    out, err = demo.stdout(), demo.stderr()
    assert "Traceback" not in err, err
    left = {pid: cmd for pid, cmd in netns_procs(box).items() if "while True" not in cmd}
    assert not left, left  # the demo shut its system down

    progress = logged_progress(run_dir / "demo.lcmlog")
    final = [p for p in progress if p.state in (State.Success, State.Failure)]
    assert final, f"no final progress of task 1 in the log ({len(progress)} messages)"
    end_s = final[0].header.sim_time_ns * 1e-9
    assert end_s > 10, end_s

    live = LIVE.findall(out)
    assert live, out
    last_t = float(live[-1][0])
    # The last line of the live view comes at the end of the task (its last running skill
    # starts within a second or so of the end), not seconds before it.
    assert end_s - 1.5 <= last_t <= end_s, f"last live line at {last_t} s, the task ended at {end_s} s\n{out}"
    # Every change of the running path the manager published is shown: each logged
    # progress message's running leaf appears in the live view at its time.
    times = {round(float(t), 2) for t, _ in live}
    changes = []
    prev = None
    for p in progress:
        running = [n for n in p.nodes if n.state == State.Running and n.type]
        key = (running[-1].type, running[-1].message) if running else None
        if running and key != prev:
            changes.append(round(p.header.sim_time_ns * 1e-9, 2))
        prev = key if running else prev
    missing = [t for t in changes if t not in times]
    assert not missing, f"{len(missing)} of {len(changes)} changes not shown, e.g. at {missing[:10]}\n{out}"

    # The tree at the end is the task's final progress: its root has ended, as the result says.
    tree = out.split("the skill tree at the end:\n", 1)[1].split("\n\n", 1)[0].splitlines()
    state = {3: "Success", 4: "Failure"}[final[0].state]
    assert tree[0].startswith(f"ClearTable [{final[0].nodes[0].processor}] {state}"), tree[0]
    assert "Running" not in tree[0]
    result = re.search(r"^  result\s+(ok|FAILED): (.*)$", out, re.M)
    assert result and result.group(2).startswith(state), out[-3000:]
    assert (rc == 0) == (result.group(1) == "ok"), (rc, out[-2000:])

    # The demo's log (skillbus record: none lost under load, both lanes) holds every
    # message the clocks announced, and the console's replay recomputes the run's own
    # session digest from it.
    from skillbus.console.replay import ReplayLog
    replay = ReplayLog(run_dir / "demo.lcmlog")
    printed = re.search(r"session digest\s+([0-9a-f]{64})", out).group(1)
    assert replay.missing == {} and replay.digest == printed, (replay.digest, printed, replay.missing)
    assert replay.tasks_at(replay.frames[-1])[0]["state"] == state


def test_an_interrupted_demo_shuts_its_system_down(box, tmp_path):  # noqa: F811
    run_dir = tmp_path / "demo"
    for sig, code in ((signal.SIGTERM, 143), (signal.SIGINT, 130)):
        demo = box.start(f"demo-{sig.name}", [sys.executable, "-m", "skillbus.cli", "demo", "--run-dir", str(run_dir)],
                         env={"SKILLBUS_NETNS": "1"})
        # (held first: the whole ClearTable can end between a live line and the signal)
        hold_task(box, 1).wait_for("held", 150, stream="stdout", what="the demo's task held (paused) while it runs")
        box.kill(demo, sig)
        rc = box.wait(demo, 60)
        err = demo.stderr()
        assert rc == code, (rc, demo.stdout()[-2000:], err)
        assert "Traceback" not in err and f"interrupted ({sig.name}): the system was shut down" in err, err
        left = {pid: cmd for pid, cmd in netns_procs(box).items()}
        assert not left, left
