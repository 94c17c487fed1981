"""The physics server's own channels (the simulator's, not the robot's): its ground truth
and the simulated fingers. A builder for the finger command and a plain view of the
state.

Channels: SB_SIM_STATE (sim_state_t, the ground truth), SB_SIM_GRIPPER_CMD
(sim_gripper_cmd_t, from the simulated gripper device), SB_SIM_CMD_REPLY
(sim_cmd_reply_t, the finger commands' replies); see docs/sim_server.md. The arm is the
robot's: skillbus.robot.messages (SB_ROBOT_*), which the physics server speaks as a real
robot's drivers do.
"""

from __future__ import annotations

from typing import Any

from skillbus.bus import channel
from skillbus.msgs import sim_gripper_cmd_t, sim_state_t
from skillbus.validate import finite, finite_all, integer


def state_channel() -> str:
    return channel("SB_SIM_STATE")


def gripper_channel() -> str:
    return channel("SB_SIM_GRIPPER_CMD")


def reply_channel() -> str:
    """The finger commands' replies (arm commands are answered on SB_ROBOT_CMD_REPLY)."""
    return channel("SB_SIM_CMD_REPLY")


def gripper_command(cmd_id: str, width: float, speed: float = 0.1, force_limit: float = 20.0) -> sim_gripper_cmd_t:
    m = sim_gripper_cmd_t()
    m.id, m.width, m.speed, m.force_limit = cmd_id, float(width), float(speed), float(force_limit)
    return m


def state_dict(s: sim_state_t) -> dict[str, Any]:
    """The state as plain data (for JSON records and assertions)."""
    return {
        "frame": s.header.frame,
        "t": s.header.sim_time_ns * 1e-9,
        "joints": dict(zip(s.joint_names, s.position)),
        "velocities": dict(zip(s.joint_names, s.velocity)),
        "efforts": dict(zip(s.joint_names, s.effort)),
        "tool_pose": list(s.tool_pose),
        "finger_width": s.finger_width,
        "finger_force": s.finger_force,
        "finger_width_target": s.finger_width_target,
        "arm_command_id": s.arm_command_id,
        "arm_moving": bool(s.arm_moving),
        "arm_tracking_error": s.arm_tracking_error,
        "objects": {o.name: {"pose": list(o.pose), "twist": list(o.twist)} for o in s.objects},
        "contacts": [{"finger": c.body_a, "object": c.body_b, "points": c.points, "normal_force": c.normal_force}
                     for c in s.contacts],
    }


def check_state(s: sim_state_t) -> None:
    """Raises BadValue unless every number of the ground truth `s` is finite, with one
    position, velocity and effort per joint, 7 numbers per pose and 6 per twist, and no
    negative contact count. (A diverging physics would publish NaN: recorded as it
    came, it would make the record invalid JSON and every comparison with it false.)
    The ranges of the fingers' values, which the gripper device acts on, are its own
    check: skillbus.can.fingers.sim_state_reading."""
    n = integer(s.num_joints, "num_joints", len(s.joint_names), len(s.joint_names))
    for field in ("position", "velocity", "effort"):
        finite_all(getattr(s, field), field, length=n)
    finite_all(s.tool_pose, "tool_pose", length=7)
    for field in ("finger_width", "finger_force", "finger_width_target", "arm_tracking_error"):
        finite(getattr(s, field), field)
    for i, o in enumerate(s.objects):
        finite_all(o.pose, f"objects[{i}].pose", length=7)
        finite_all(o.twist, f"objects[{i}].twist", length=6)
    for i, c in enumerate(s.contacts):
        integer(c.points, f"contacts[{i}].points", 0)
        finite(c.normal_force, f"contacts[{i}].normal_force")
