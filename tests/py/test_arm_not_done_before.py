"""Arm.not_done_before: when a trajectory sent by Arm.execute can be finished at the
earliest (what the demo's motions idle until, PrimitiveBase.idle_until): only once the
robot accepted it, and on the wall clock never more than STALE_S / 2 ahead."""

from __future__ import annotations

import pytest

from skillbus import tick_context
from skillbus.bus import open_bus
from skillbus.msgs import motion_plan_t, robot_cmd_reply_t
from skillbus.robot.arm import Arm
from skillbus.robot.messages import traj_point


class Participant:  # what Arm needs of a lockstep participant: subscribe and publish
    def __init__(self) -> None:
        self.sent: list = []

    def subscribe(self, ch, handler, latest_only=False) -> None:
        pass

    def publish(self, ch, msg) -> None:
        self.sent.append((ch, msg))


def plan(seconds: float) -> motion_plan_t:
    p = motion_plan_t()
    p.ok = True
    p.joint_names, p.num_joints = ["j1"], 1
    p.points = [traj_point(0.0, [0.0]), traj_point(seconds, [1.0])]
    p.num_points = 2
    return p


def reply(cmd_id: str, accepted: bool) -> bytes:
    r = robot_cmd_reply_t()
    r.id, r.command, r.accepted, r.error = cmd_id, "arm", accepted, "" if accepted else "joint limits"
    return r.encode()


@pytest.fixture
def lockstep_arm():
    return Arm(open_bus("memq://"), participant=Participant())


def sent_at(arm: Arm, sim_s: float, cmd_id: str, seconds: float) -> None:
    with tick_context.ticking(int(sim_s * 50), int(sim_s * 1e9)):
        arm.execute(plan(seconds), cmd_id)


def test_a_trajectory_the_robot_accepted_cannot_end_before_its_last_point(lockstep_arm):
    sent_at(lockstep_arm, 2.0, "go", 1.5)
    assert lockstep_arm.not_done_before("go") is None  # no answer from the robot yet
    lockstep_arm._on_reply(reply("go", True))
    with tick_context.ticking(110, 2_200_000_000):
        assert lockstep_arm.not_done_before("go") == pytest.approx(3.5)


def test_a_refused_or_unknown_command_gives_no_time(lockstep_arm):
    sent_at(lockstep_arm, 2.0, "go", 1.5)
    lockstep_arm._on_reply(reply("go", False))
    assert lockstep_arm.not_done_before("go") is None
    lockstep_arm._on_reply(reply("other", True))
    assert lockstep_arm.not_done_before("other") is None  # accepted, but not a trajectory sent here


def test_on_the_wall_clock_it_looks_no_further_than_half_the_silence_a_driver_is_allowed():
    arm = Arm(open_bus("memq://"))
    sent_at(arm, 10.0, "go", 30.0)
    arm._on_reply(reply("go", True))
    with tick_context.ticking(600, 12_000_000_000):
        assert arm.not_done_before("go") == pytest.approx(12.0 + Arm.STALE_S / 2)
