"""Faults are named where they show: a physics server (the arm's driver) killed while the
arm moves fails the moving skill within seconds (after 0.5 s of silence), saying the
driver went silent, not 'not at ... after 20 s'. The whole system on the wall clock,
every part a real process."""

import sys
import time

from skillbus.system import programs, start
from skillbus.waiting import wait_until


def test_a_killed_arm_driver_is_named_by_the_moving_skill(sandbox, tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    # (the physics at 0.4 of real time: the move lasts several seconds, so the kill lands
    # while it runs on a loaded machine too)
    procs = start(sandbox, programs(run, task=None, lockstep=False, extra_sim=("--speed", "0.4")), run)
    cli = [sys.executable, "-m", "skillbus.cli"]

    def listed() -> bool:
        p = sandbox.start(f"skills-{time.monotonic_ns()}", [*cli, "skills"])
        return sandbox.wait(p, 30) == 0 and "MoveArm" in p.stdout()

    wait_until(listed, 60, "the skills registered")
    move = sandbox.start("move", [*cli, "run", "MoveArm", "-p", "Arm=skiros:Arm-8", "-p", "Target=skiros:Bin-5",
                                  "-p", "Height=0.45", "--timeout", "60"])
    move.wait_for("started", 30, stream="stdout")
    time.sleep(0.5)  # the arm is on its way
    sandbox.kill(procs["sim"])
    killed = time.monotonic()
    assert sandbox.wait(move, 30) == 1, move.stdout() + move.stderr()
    out = move.stdout()
    assert "the robot arm's driver went silent: no state on SB_ROBOT_ARM_STATE for" in out, out
    assert time.monotonic() - killed < 10.0  # (named from the silence, long before the run's 60 s; load's delays in it)
