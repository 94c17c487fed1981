"""The end of a lockstep run is decided through lockstep: the skill manager, started with
a task and --end-session-after-task N, asks the clock master (lockstep_end_t on
SB_LOCKSTEP_END) to end the session N frames after the task ended, at the same frame on
every run, whatever the task's outcome."""

import sys

from conftest import last_json
from skillbus import paths
from skillbus.netns import Sandbox
from test_skills import LIBS, mgr_binary

LIMIT = 5000  # frames the clock would run without the request (50 s of sim time)


def session(tmp_path, name: str, start: str) -> tuple[dict, dict]:
    with Sandbox(log_dir=tmp_path / name) as box:
        clock = box.start("clock", [paths.binary("sb_clock"), "--frames", str(LIMIT), "--participants",
                                    "skill_mgr,proc1"])
        mgr = box.start("skill_mgr", [mgr_binary(), "--start", start, "--end-session-after-task", "5"])
        box.start("proc1", [sys.executable, "-m", "skillbus.cli", "skills-process", "--lockstep", "--name", "proc1",
                            "--library", "flow_skills"], env={"PYTHONPATH": str(LIBS)})
        assert box.wait(clock, 120) == 0, clock.stdout() + clock.stderr()[-2000:]
        assert box.wait(mgr, 30) == 0, mgr.stderr()[-2000:]
        return last_json(clock.stdout()), last_json(mgr.stdout())


def test_the_task_ends_the_session_at_the_same_frame_every_run(tmp_path):
    runs = [session(tmp_path, f"run{i}", "Wait Ticks=5") for i in range(2)]
    for clock, mgr in runs:
        assert mgr["tasks"]["1"].startswith("Success"), mgr
        assert clock["frames"] < 100, clock  # 5 ticks of 40 ms and 5 frames of grace, not 5000 frames
    assert runs[0][0]["frames"] == runs[1][0]["frames"]
    assert runs[0][0]["digest"] == runs[1][0]["digest"]


def test_a_task_that_cannot_start_ends_the_session_too(tmp_path):
    clock, mgr = session(tmp_path, "bad", "Wait Ticks=many")
    assert mgr["tasks"]["1"] == "Failure: parameter Ticks: 'many' is not a int", mgr
    assert clock["frames"] < 100, clock
