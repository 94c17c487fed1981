"""Builders for the physics server's commands and a plain view of its state.

Channels: SB_SIM_ARM_CMD (sim_arm_cmd_t), SB_SIM_GRIPPER_CMD (sim_gripper_cmd_t),
SB_SIM_STATE (sim_state_t), SB_SIM_CMD_REPLY (sim_cmd_reply_t); see docs/sim_server.md.
"""

from __future__ import annotations

from typing import Any, Sequence

from skillbus.bus import channel
from skillbus.msgs import sim_arm_cmd_t, sim_gripper_cmd_t, sim_state_t, sim_traj_point_t


def state_channel() -> str:
    return channel("SB_SIM_STATE")


def arm_channel() -> str:
    return channel("SB_SIM_ARM_CMD")


def gripper_channel() -> str:
    return channel("SB_SIM_GRIPPER_CMD")


def reply_channel() -> str:
    return channel("SB_SIM_CMD_REPLY")


def arm_command(cmd_id: str, joints: Sequence[str],
                points: Sequence[tuple[float, Sequence[float]]]) -> sim_arm_cmd_t:
    """A timed joint trajectory: points are (seconds from start, positions). A single
    point at 0 s is a position target timed by the velocity limits."""
    m = sim_arm_cmd_t()
    m.id = cmd_id
    m.joint_names = list(joints)
    m.num_joints = len(m.joint_names)
    m.points = []
    for t, q in points:
        p = sim_traj_point_t()
        p.time_from_start_ns = int(round(t * 1e9))
        p.positions = [float(x) for x in q]
        p.num_positions = len(p.positions)
        p.velocities, p.num_velocities = [], 0
        m.points.append(p)
    m.num_points = len(m.points)
    return m


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
