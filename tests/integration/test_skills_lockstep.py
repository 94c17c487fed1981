"""A compound skill whose primitives live in two skill processes, in lockstep."""

import re
import sys
import time

from conftest import last_json
from skillbus import paths
from skillbus.netns import Sandbox
from test_skills import LIBS, mgr_binary

FRAMES = 1200  # 12 s of sim time; the task needs 20 + 30 + 5 ticks of 40 ms (2.2 s)


def session(box, frames=FRAMES, ack_timeout_ms=5000, env_b=None):
    clock = box.start("clock", [paths.binary("sb_clock"), "--frames", str(frames), "--participants",
                                "skill_mgr,proc_a,proc_b", "--ack-timeout-ms", str(ack_timeout_ms)])
    mgr = box.start("skill_mgr", [mgr_binary(), "--start", "Both"])
    extra = {"proc_a": {}, "proc_b": env_b or {}}
    procs = {n: box.start(n, [sys.executable, "-m", "skillbus.cli", "skills-process", "--lockstep", "--name", n,
                              "--library", lib], env={"PYTHONPATH": str(LIBS), **extra[n]})
             for n, lib in (("proc_a", "lockstep_a"), ("proc_b", "lockstep_b"))}
    return clock, mgr, procs


def test_runs_to_success_twice_with_the_same_digest(tmp_path):
    runs = []
    for i in range(2):
        with Sandbox(log_dir=tmp_path / f"run{i}") as box:
            clock, mgr, procs = session(box)
            assert box.wait(clock, 120) == 0, clock.stdout() + clock.stderr()[-2000:]
            assert box.wait(mgr, 30) == 0, mgr.stderr()[-2000:]
            runs.append((last_json(clock.stdout()), last_json(mgr.stdout())))
    for clock, mgr in runs:
        assert mgr["tasks"] == {"1": "Success: all succeeded"}, mgr
    assert runs[0][0]["digest"] == runs[1][0]["digest"]
    assert runs[0][1]["digest"] == runs[1][1]["digest"]


def test_killing_a_skill_process_fails_the_task_by_name_and_a_restart_succeeds(tmp_path):
    with Sandbox(log_dir=tmp_path / "killed") as box:
        # `other` ticks for ever here: the task can only end by the kill (with 30 ticks, at the
        # clock's pace, it sometimes ended before the kill landed and the task succeeded).
        clock, mgr, procs = session(box, frames=100_000, ack_timeout_ms=1500,
                                    env_b={"LOCKSTEP_B_OTHER_TICKS": "1000000"})
        procs["proc_b"].wait_for("other started", 60, interval=0.01)
        box.kill(procs["proc_b"])
        killed = time.monotonic()
        # Either the manager's tick of `other` times out, or the master stops the session
        # because proc_b stopped acknowledging frames: both name proc_b.
        mgr.wait_for(re.compile(r"task 1: Both Failure: .*(skill process proc_b did not answer the tick of other "
                                r"within 1\.0 s|no ack for frame \d+ from participant\(s\) proc_b within 1\.5 s)"),
                     10, interval=0.01)
        failed_at = time.monotonic()
        assert failed_at - killed < 5.0  # (the 1.0 s or 1.5 s timeout, and a loaded machine's delays)
        # the dead participant also stops the lockstep session, named
        assert box.wait(clock, 30) == 1
        assert "proc_b" in last_json(clock.stdout())["error"]
    with Sandbox(log_dir=tmp_path / "restarted") as box:  # the supervisor's restart: the same task succeeds
        clock, mgr, procs = session(box)
        assert box.wait(clock, 120) == 0
        box.wait(mgr, 30)
        assert last_json(mgr.stdout())["tasks"] == {"1": "Success: all succeeded"}


def test_frames_that_do_not_divide_the_tick_period_fail_the_session_naming_both(tmp_path):
    # 30 ms frames and the manager's 40 ms ticks: skills would tick only every 120 ms.
    # Before, the session ran so, silently; now the manager fails its first frame.
    with Sandbox(log_dir=tmp_path / "frames") as box:
        clock = box.start("clock", [paths.binary("sb_clock"), "--frames", "50", "--participants", "skill_mgr",
                                    "--period-ms", "30"])
        mgr = box.start("skill_mgr", [mgr_binary()])
        assert box.wait(clock, 60) != 0, clock.stdout()
        box.wait(mgr, 30)
    why = "the clock's frames of 30 ms do not divide the skill manager's tick period of 40 ms"
    assert why in clock.stdout() + clock.stderr(), clock.stdout() + clock.stderr()[-2000:]
    assert why in mgr.stderr(), mgr.stderr()[-2000:]


def test_a_skill_process_joins_lockstep_once_its_libraries_warm_ups_ended(tmp_path):
    # A library's warm-up (TaskPlan imports its planner, seconds of CPU) still running
    # during frames took a core and the interpreter's lock from each: the demo ran 11x real
    # time instead of 15x. The process now joins after it; its first tick sees it ended.
    with Sandbox(log_dir=tmp_path / "warm") as box:
        clock = box.start("clock", [paths.binary("sb_clock"), "--frames", "100", "--participants",
                                    "skill_mgr,warm", "--join-timeout-ms", "30000"])
        mgr = box.start("skill_mgr", [mgr_binary(), "--start", "Warmed"])
        box.start("warm", [sys.executable, "-m", "skillbus.cli", "skills-process", "--lockstep", "--name", "warm",
                           "--library", "lockstep_warm"], env={"PYTHONPATH": str(LIBS)})
        assert box.wait(clock, 60) == 0, clock.stdout() + clock.stderr()[-2000:]
        assert box.wait(mgr, 30) == 0, mgr.stderr()[-2000:]
        assert last_json(mgr.stdout())["tasks"] == {"1": "Success: the warm-up had ended"}, mgr.stdout()[-2000:]
