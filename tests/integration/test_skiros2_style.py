"""A skill library written for SkiROS2 (skill_libs/skiros2_style_lib.py: only its import
lines differ) runs and succeeds through the real processes: poses set with setData in one
skill and read with getData in the next, a monitor that never ends under ParallelFs,
nested anonymous processors, and a node's own pre-condition (self.skill(...,
preconditions=[...])), which holds or stops the node naming it."""

import sys

from test_skills import LIBS, cli, mgr_binary, start_system, start_wm


def test_a_skiros2_library_runs_unchanged_and_succeeds(sandbox, tmp_path):
    start_wm(sandbox, tmp_path / "wm")
    start_system(sandbox, "skiros2_style_lib", world_model=True, timeout=60)
    rc, out, err = cli(sandbox, "run", "Arrange", "-p", "Object=skiros:Cube-2", "--timeout", "60", timeout=90)
    assert rc == 0, out + err
    lines = [line.strip() for line in out.splitlines()]
    assert lines[-1] == "task 1: Success: all succeeded", out
    assert any(line.startswith("PoseReader Success: found at (0.25, -0.1, 0.6)") for line in lines), out
    assert any(line.startswith("(ParallelFs) Success") for line in lines), out  # the monitor stopped, not failed
    assert sum(1 for line in lines if line.startswith("Work Success: worked 3 ticks")) == 2, out
    rc, tree, err = cli(sandbox, "wm", "get", "skiros:Cube-2")
    assert rc == 0 and "0.25" in tree, tree + err  # the pose is the world model's now

    # a node's own pre-condition, named by the remapped key: holds for a cube...
    rc, out, err = cli(sandbox, "run", "GuardedRead", "-p", "Target=skiros:Cube-2", "--timeout", "60", timeout=90)
    assert rc == 0 and "PoseReader Success" in out, out + err
    # ...and stops the node, naming it, when the cube is no cylinder
    rc, out, err = cli(sandbox, "run", "GuardedRead", "-p", "Target=skiros:Cube-2", "-p", "Strict=true",
                       "--timeout", "60", timeout=90)
    assert rc == 1 and "TargetIsA" in out, out + err


def test_the_next_skill_is_handed_what_the_last_one_wrote_however_late_the_change_stream(sandbox, tmp_path):
    # The world model publishes each change 6 s after its commit: a change stream that
    # lags the commit's reply (on DDS the two travel on different topics, and the reply
    # may come first). The skill process's own replica gives up waiting after 5 s and
    # reads the world anew; the manager's waits 1 s, then reads it anew before the next
    # skill starts. So PoseWriter's pose reaches PoseReader (before, the manager's replica
    # was simply behind, and PoseReader was handed the cube where it had been).
    start_wm(sandbox, tmp_path / "wm", "--hold-changes-ms", "6000")
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock", "--tick-timeout-ms", "20000"])
    proc = sandbox.start("proc1", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "proc1",
                                   "--library", "skiros2_style_lib", "--world-model"], env={"PYTHONPATH": str(LIBS)})
    proc.wait_for("registered", 60)
    rc, out, err = cli(sandbox, "run", "Arrange", "-p", "Object=skiros:Cube-2", "--timeout", "60", timeout=90)
    assert rc == 0, out + err
    assert any(line.strip().startswith("PoseReader Success: found at (0.25, -0.1, 0.6)") for line in out.splitlines()), out
