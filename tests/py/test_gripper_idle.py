"""The gripper skills idle while the fingers open (GripperPrimitive._idle_while_travelling):
no tick before the fingers could be open at the speed the driver set, at most
FAULT_NOTICE_S at a time; a close or a grasp, which ends wherever the fingers touch
something, is ticked as always. The driver is a stand-in here (its status is what the test
says); the manager's side of idling is tests/integration/test_idle_ticks.py, the demo's
(same state digest, fewer ticks) bench/pick_and_place.py."""

from __future__ import annotations

import pytest

from skillbus import tick_context
from skillbus.can import cia402 as c
from skillbus.can.driver import GripperStatus
from skillbus.skill import Element, State
from skillbus.skills import gripper_primitive as gp
from skillbus.skills.gripper import grasp, gripper_close, release

VELOCITY = 50_000  # um/s, the driver's default 0x6081


class FakeDriver:
    """What the primitive reads of a GripperDriver: its status and the speed it set."""

    def __init__(self, velocity: float = VELOCITY) -> None:
        self.velocity = velocity
        self.now = GripperStatus(state=c.OPERATION_ENABLED, position_um=80_000)
        self.commands: list[int] = []

    def status(self) -> GripperStatus:
        return self.now

    def command(self, width_um: int) -> None:
        self.commands.append(width_um)


def cube(side: object) -> Element:
    e = Element("skiros:Product", "cube", "skiros:Cube-1")
    if side is not None:
        e.setProperty("skiros:Size", side)
    return e


def started(cls, driver: FakeDriver, side: object = 0.05):
    """An instance after its first tick at sim time 0 (the set-point sent)."""
    skill = cls()
    if "Object" in skill.params:
        skill.params["Object"].value = cube(side)
    with tick_context.ticking(0, 0):
        skill.gripper = driver
        skill.command = skill.params["Command"].value
        skill.sent = skill.written = False
        skill.recovering = ""
        skill.started_at = 0.0
        skill.wmi = None
        assert skill.execute() == State.Running and skill.message.endswith("sent")
    return skill


def execute_at(skill, t: float) -> tuple[State, float]:
    """One execute() at sim time `t`: its state and the time it idles until (0: none)."""
    skill._idle_until_ns = 0
    with tick_context.ticking(int(t * 50), int(round(t * 1e9))):
        state = skill.execute()
    return state, skill._idle_until_ns * 1e-9


def moving(driver: FakeDriver, position_um: int) -> None:
    driver.now = GripperStatus(state=c.OPERATION_ENABLED, position_um=position_um, grip=c.GRIP_MOVING)


def test_a_release_idles_until_the_fingers_could_be_open_capped_for_faults():
    d = FakeDriver()
    skill = started(release, d)
    moving(d, 50_000)  # 30 mm to go at 50 mm/s: 0.6 s at the earliest, less the margin
    state, until = execute_at(skill, 1.0)
    assert state == State.Running and "moving" in skill.message
    assert until == pytest.approx(1.0 + gp.FAULT_NOTICE_S)  # (0.5 s away: capped)
    moving(d, 72_000)  # 8 mm: 0.16 s, less 0.1
    assert execute_at(skill, 1.2)[1] == pytest.approx(1.2 + 0.16 - gp.ARRIVAL_MARGIN_S)
    moving(d, 76_000)  # 4 mm: 0.08 s is within the margin: ticked as always
    assert execute_at(skill, 1.3)[1] == 0


@pytest.mark.parametrize("cls, side", [(grasp, 0.05), (grasp, None), (grasp, float("nan")), (gripper_close, None)],
                         ids=["grasp", "grasp-no-size", "grasp-nan-size", "close"])
def test_a_grasp_or_close_may_touch_something_at_any_width_and_is_ticked_as_always(cls, side):
    """(A 50 mm cube turned by 20 degrees is 64 mm across the fingers: a grasp that idled
    until the fingers reached 50 mm would skip the tick that finds it gripped.)"""
    d = FakeDriver()
    skill = started(cls, d, side=side)
    moving(d, 79_000)
    state, until = execute_at(skill, 1.0)
    assert (state, until) == (State.Running, 0)


def test_no_idling_on_a_status_from_before_the_command_or_without_a_speed():
    d = FakeDriver()
    skill = started(release, d)
    moving(d, 50_000)
    d.now.fresh = False  # (it may still show the previous move)
    assert execute_at(skill, 1.0)[1] == 0
    d = FakeDriver(velocity=0)
    skill = started(release, d)
    moving(d, 50_000)
    assert execute_at(skill, 1.0)[1] == 0


def test_the_idle_ends_by_the_commands_timeout():
    d = FakeDriver()
    skill = started(release, d)
    moving(d, 10_000)
    t = gp.TIMEOUT_S - 0.05
    assert execute_at(skill, t)[1] == pytest.approx(gp.TIMEOUT_S)
    moving(d, 15_000)
    state, _ = execute_at(skill, gp.TIMEOUT_S + 0.04)  # (the first tick past it)
    assert state == State.Failure and "no result within" in skill.message


def test_a_fault_on_the_way_fails_the_first_tick_after_the_idle():
    """What the idle trades: a fault is named at the next tick, FAULT_NOTICE_S at most."""
    d = FakeDriver()
    skill = started(release, d)
    moving(d, 40_000)
    _, until = execute_at(skill, 1.0)
    assert until == pytest.approx(1.0 + gp.FAULT_NOTICE_S)  # (0.8 s from open: the cap holds)
    d.now = GripperStatus(state=c.FAULT, position_um=45_000, faults=["EMCY 0x8611 following error"])
    state, _ = execute_at(skill, until)
    assert state == State.Failure and "following error" in skill.message
