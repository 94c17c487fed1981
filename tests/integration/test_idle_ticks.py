"""A primitive that idles (PrimitiveBase.idle_until) is not ticked until its time, while a
broken hold-condition and a stop still reach it at once: the real manager, skill process
and world model (wall clock). The skill process's reply is tests/py/test_idle_until.py;
under lockstep, the pick-and-place demo (its moves idle until their trajectories end,
with the same physics bit for bit: tests/integration/test_pick_and_place.py)."""

import re
import signal
import sys
import time

import pytest

from test_skill_conditions import start_condition_system
from conftest import last_json
from test_skills import LIBS, cli


@pytest.fixture
def system(sandbox, tmp_path):
    return start_condition_system(sandbox, tmp_path / "wm")


def test_an_idle_primitive_is_executed_again_only_when_its_time_has_come(system):
    t0 = time.monotonic()
    rc, out, err = cli(system, "run", "IdleWait", "-p", "Seconds=1.0", "--timeout", "20")
    took = time.monotonic() - t0
    assert rc == 0, out + err
    # START's execute, then the first tick at or after its time: 25 Hz ticks would have run
    # it 26 times (a loaded machine may add one tick before the time, none more)
    n = int(re.search(r"waited, executed (\d+) times", out).group(1))
    assert 2 <= n <= 3, out
    assert took >= 1.0, took


def test_a_broken_hold_condition_stops_an_idle_primitive(system):
    run = system.start("run", [sys.executable, "-m", "skillbus.cli", "run", "Hold", "--label", "idle_hold", "-p",
                               "Object=skiros:Cube-3", "--timeout", "30", "--watch"], env={"PYTHONPATH": str(LIBS)})
    run.wait_for("idling", 20, stream="stdout")
    code = ("from skillbus.bus import open_bus; from skillbus.world import WorldModelInterface as W; "
            "W(open_bus(), 't').set_relation('skiros:Table-1','skiros:contain','skiros:Cube-3', False)")
    edit = system.start("edit", [sys.executable, "-c", code])
    assert system.wait(edit, 30) == 0
    t0 = time.monotonic()
    assert system.wait(run, 20) == 1  # not 400 s later
    assert time.monotonic() - t0 < 15
    assert "hold-condition StillOnTable failed" in run.stdout(), run.stdout()


def test_a_stop_reaches_an_idle_primitive_at_once(system):
    run = system.start("run", [sys.executable, "-m", "skillbus.cli", "run", "Hold", "--label", "idle_hold", "-p",
                               "Object=skiros:Cube-3", "--timeout", "30", "--watch"], env={"PYTHONPATH": str(LIBS)})
    run.wait_for("idling", 20, stream="stdout")
    rc, out, _ = cli(system, "stop", "1")
    assert rc == 0 and "stopping" in out
    assert system.wait(run, 20) == 1
    assert "Failure" in run.stdout() and "preempted" in run.stdout(), run.stdout()


def test_a_parameter_a_sibling_changes_reaches_an_idle_primitive_at_once(system):
    # flag_watch idles for 400 s; flag_raise (beside it, ParallelFf) raises Flag at its
    # third tick: the changed parameter gets flag_watch ticked, and it sees the flag.
    rc, out, err = cli(system, "run", "WatchFlag", "--verbose", "--timeout", "20")
    assert rc == 0, out + err
    assert "saw the flag" in out, out


def test_a_killed_skill_process_fails_its_idle_primitive_once_the_manager_drops_it(system):
    run = system.start("run", [sys.executable, "-m", "skillbus.cli", "run", "Hold", "--label", "idle_hold", "-p",
                               "Object=skiros:Cube-3", "--timeout", "60", "--watch"], env={"PYTHONPATH": str(LIBS)})
    run.wait_for("idling", 20, stream="stdout")
    system.kill(next(p for p in system.procs if p.name == "proc1"), signal.SIGKILL)
    # dropped after 3 s without a heartbeat (docs/skills.md, Liveness); not 400 s later
    assert system.wait(run, 30) == 1
    assert "skill process proc1 stopped answering while running idle_hold" in run.stdout(), run.stdout()


def manager_summary(system) -> dict:
    """The manager's summary, once it is stopped."""
    mgr = next(p for p in system.procs if p.name == "skill_mgr")
    system.kill(mgr, signal.SIGTERM)
    system.wait(mgr, 20)
    return last_json(mgr.stdout())


def test_a_primitive_ends_within_the_tick_that_finishes_it_and_the_manager_sends_no_end(system):
    """The skill process runs onEnd in the tick that finished a primitive and in its
    PREEMPT (as SkiROS2), and says so in its reply: a round trip less at every end
    (tests/py/test_tick_ends.py is the skill process's side)."""
    rc, out, err = cli(system, "run", "IdleWait", "-p", "Seconds=0.2", "--timeout", "20")
    assert rc == 0 and "waited" in out, out + err
    run = system.start("run", [sys.executable, "-m", "skillbus.cli", "run", "Hold", "--label", "idle_hold", "-p",
                               "Object=skiros:Cube-3", "--timeout", "30", "--watch"], env={"PYTHONPATH": str(LIBS)})
    run.wait_for("idling", 20, stream="stdout")
    rc, out, _ = cli(system, "stop", "2")
    assert rc == 0 and "stopping" in out
    assert system.wait(run, 20) == 1 and "preempted" in run.stdout(), run.stdout()
    sent = manager_summary(system)["ticks_sent"]
    assert sent["start"] == 2 and sent["preempt"] == 1, sent
    assert sent["end"] == 0, sent  # (one a primitive before: 2)
