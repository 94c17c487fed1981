"""A move of the skills library (skillbus.skills.manipulation._ArmMotion: MoveArm, LiftArm,
...) that fails on the way stops the arm where it is, as a stop (preempt) does: before, a
move that timed out or whose robot went silent failed while its trajectory played on, and
an exception in execute() left it playing too. A stand-in arm only here (a unit test)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from skillbus import tick_context
from skillbus.skill import Element, ParamTypes, SkillDescription, State
from skillbus.skills import manipulation


class Arm:
    def __init__(self) -> None:
        self.sent: list[str] = []
        self.held: list[str] = []
        self.silent = ""
        self.finished_raises = False

    def plan(self, pose, cartesian, held=None):
        return SimpleNamespace(ok=True, error="")

    def execute(self, plan, cmd):
        self.sent.append(cmd)

    def silence(self):
        return self.silent

    def finished(self, cmd):
        if self.finished_raises:
            raise RuntimeError("a bug")
        return False, ""

    def not_done_before(self, cmd):
        return None

    def hold(self, cmd):
        self.held.append(cmd)
        return [0.0]


class Probe(SkillDescription):
    def createDescription(self):
        self.addParam("Arm", Element("skiros:Arm"), ParamTypes.Required)


class probe_move(manipulation._ArmMotion):
    def createDescription(self):
        self.setDescription(Probe(), "probe_move")

    def target(self):
        return [0.3, 0.0, 0.5, 0.0, 1.0, 0.0, 0.0], False, "the probe's target"


@pytest.fixture
def move(monkeypatch):
    arm = Arm()
    monkeypatch.setattr(manipulation.arm_service, "arm", lambda: arm)
    monkeypatch.setattr(manipulation, "held_box", lambda wmi, arm_id: (0.0, 0.0, 0.0))
    skill = probe_move()
    skill.params["Arm"].value = Element("skiros:Arm", "arm", "skiros:Arm-1")
    with tick_context.ticking(0, 0):
        skill.onStart()
        assert skill.execute() == State.Running and arm.sent
    return skill, arm


def at(seconds: float, fn):
    with tick_context.ticking(int(seconds * 50), int(seconds * 1e9)):
        return fn()


def test_a_move_that_times_out_stops_the_arm(move):
    skill, arm = move
    assert at(10.0, skill.execute) == State.Running and arm.held == []
    assert at(manipulation.MOVE_TIMEOUT_S + 1, skill.execute) == State.Failure
    assert skill.message.endswith("after 20 s; the arm was stopped where it was"), skill.message
    assert len(arm.held) == 1
    skill.onEnd()
    assert len(arm.held) == 1  # once


def test_a_move_whose_robot_falls_silent_stops_the_arm(move):
    skill, arm = move
    arm.silent = "the arm's driver has been silent for 2.0 s"
    assert at(1.0, skill.execute) == State.Failure and len(arm.held) == 1, skill.message
    assert skill.message.endswith("silent for 2.0 s; the arm was stopped where it was"), skill.message


def test_an_exception_on_the_way_stops_the_arm_at_its_end(move):
    skill, arm = move
    arm.finished_raises = True
    with pytest.raises(RuntimeError):
        at(1.0, skill.execute)
    skill.onEnd()  # (the skill process fails the skill and runs its onEnd: test_tick_ends.py)
    assert len(arm.held) == 1


def test_a_move_that_arrives_holds_nothing(move):
    skill, arm = move
    arm.finished = lambda cmd: (True, "")
    assert at(1.0, skill.execute) == State.Success
    skill.state = State.Success
    skill.onEnd()
    assert arm.held == []


def test_a_move_the_robot_refuses_holds_nothing(move):
    skill, arm = move
    arm.finished = lambda cmd: (True, "joint1 target 9 is outside +-1.0 rad")
    assert at(1.0, skill.execute) == State.Failure and "rejected" in skill.message
    skill.onEnd()  # (failed: but nothing moves)
    assert arm.held == []
