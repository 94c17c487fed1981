"""GET /api/sim without a page open (a script polling the robot's state): the console goes
on hearing the physics state for a while after each call, and says how old the state is.
Before, the next chore (every 0.1 s) unsubscribed it again: a polling script got a 404,
then the state of around its previous call, with nothing saying it was old. LiveSim on a
stand-in bus (a unit test)."""

from __future__ import annotations

from skillbus import paths
from skillbus.console import views3d
from skillbus.console.scene3d import Scene3D
from skillbus.console.views3d import LiveSim
from skillbus.msgs import sim_state_t
from support.stand_in_bus import StandInBus


def deliver(bus: StandInBus, frame: int) -> bool:
    """A physics state of `frame` to whoever hears SB_SIM_STATE; whether someone did."""
    s = sim_state_t()
    s.header.frame = frame
    return bus.deliver("SB_SIM_STATE", s.encode())


def test_a_script_polling_the_state_without_a_page_gets_the_latest_with_its_age(monkeypatch):
    now = [1000.0]
    monkeypatch.setattr(views3d.time, "monotonic", lambda: now[0])
    bus = StandInBus()
    sim = LiveSim(bus, Scene3D(paths.demo_scene()), lambda event: None)
    assert sim.latest() is None  # nothing heard yet
    now[0] += 0.1
    sim.send(False)  # the chore, no page open
    assert deliver(bus, 7), "the state is no longer heard right after the call"
    now[0] += 0.5
    view = sim.latest()
    assert view["frame"] == 7 and view["age_s"] == 0.5, view
    now[0] += views3d.ASKED_GRACE_S + 1  # no call for a while: not heard any more
    sim.send(False)
    assert not deliver(bus, 8)
    view = sim.latest()  # the old state, and how old it is
    assert view["frame"] == 7 and view["age_s"] > views3d.ASKED_GRACE_S, view
