"""A lockstep program asked to stop (SIGTERM from supervisord, Ctrl-C) stops at once, also
while its lockstep waits: a master for a join or an ack, a participant for its clock.

Before, the C++ programs looked at the request only between frames, so a program waiting
ended when a lockstep timeout ended the wait: 7-60 s later, with an error, or killed by
supervisord after its stopwaitsecs. Stopping the demo's system (skills first, by priority)
left the master waiting for the skill process's ack and each program after it waiting for
a clock: an interrupted `skillbus demo` took most of a minute under load.
"""

from __future__ import annotations

import signal
import time

import pytest

from conftest import last_json
from skillbus import paths

AT_ONCE_S = 2.0  # what "at once" is given on a loaded machine; the waits it cuts are 5-60 s


def stopped_within(box, proc, sig: int) -> tuple[int, float]:
    """Signals `proc`; its exit code and how long it took to end."""
    t0 = time.monotonic()
    box.kill(proc, sig)
    rc = box.wait(proc, 90)
    return rc, time.monotonic() - t0


def waiting_programs(tmp_path) -> dict[str, tuple[list[str], str]]:
    """Each program waiting for its session, and what it writes once it waits."""
    return {
        "master-for-a-join": ([str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()), "--frame-ms", "20",
                               "--participants", "nobody", "--join-timeout-ms", "60000"], "lockstep master"),
        "wm-for-a-clock": ([str(paths.binary("wm_server")), "--data", str(tmp_path / "wm"), "--scene",
                            str(paths.REPO_ROOT / "deploy" / "scenes" / "demo.ttl")], "serving"),
        "manager-for-a-clock": ([str(paths.binary("skill_mgr"))], "serving"),
        "map-for-a-clock": ([str(paths.binary("map_server")), "--lockstep", "map", "--exit-with-session"],
                            "joining the lockstep"),
    }


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["sigterm", "sigint"])
@pytest.mark.parametrize("case", ["master-for-a-join", "wm-for-a-clock", "manager-for-a-clock", "map-for-a-clock"])
def test_a_program_waiting_for_its_session_stops_at_once(sandbox, tmp_path, case, sig):
    argv, waiting = waiting_programs(tmp_path)[case]
    p = sandbox.start(case, argv)
    p.wait_for(waiting, 60, what=f"{case} started")
    time.sleep(0.3)  # (in its wait)
    rc, took = stopped_within(sandbox, p, sig)
    err = p.stderr()
    assert rc == 0 and took < AT_ONCE_S, (rc, round(took, 2), err[-2000:])
    assert "stopped before the first frame (asked to" in err, err[-2000:]
    if case != "map-for-a-clock":  # (the map server's summary is about its map)
        assert last_json(p.stdout())["ok"] is True


def test_a_session_whose_master_waits_for_an_ack_stops_at_once(sandbox, tmp_path):
    # Frames run with two participants; one is frozen (SIGSTOP), so the master waits for its
    # ack and the other for the next clock. Each of them stops at once when asked, the
    # master telling the frozen one, which ends cleanly once it runs again.
    sim = sandbox.start("sim", [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()), "--frame-ms", "20",
                                "--participants", "skill_mgr,wm", "--join-timeout-ms", "60000",
                                "--ack-timeout-ms", "60000"])
    wm = sandbox.start("wm", [str(paths.binary("wm_server")), "--data", str(tmp_path / "wm"), "--scene",
                              str(paths.REPO_ROOT / "deploy" / "scenes" / "demo.ttl")])
    mgr = sandbox.start("skill_mgr", [str(paths.binary("skill_mgr"))])
    sim.wait_for("starting frames", 60, what="the session's frames started")
    time.sleep(0.3)
    sandbox.kill(mgr, signal.SIGSTOP)
    time.sleep(0.5)  # the master now waits for the manager's ack, the world model for a clock

    rc, took = stopped_within(sandbox, wm, signal.SIGTERM)
    assert rc == 0 and took < AT_ONCE_S, (rc, round(took, 2), wm.stderr()[-2000:])
    assert "(asked to, while waiting for the clock of frame" in wm.stderr(), wm.stderr()[-2000:]

    rc, took = stopped_within(sandbox, sim, signal.SIGTERM)
    err = sim.stderr()
    assert rc == 0 and took < AT_ONCE_S, (rc, round(took, 2), err[-2000:])
    assert "(asked to, while waiting for the ack of skill_mgr" in err, err[-2000:]
    summary = last_json(sim.stdout())
    assert summary["ok"] is True and summary["frames"] > 0, summary

    sandbox.kill(mgr, signal.SIGCONT)  # it reads the master's stop, which waited in its socket
    assert sandbox.wait(mgr, 30) == 0, mgr.stderr()[-2000:]
    assert last_json(mgr.stdout())["ok"] is True
