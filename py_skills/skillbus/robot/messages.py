"""The robot's channels and a builder for its arm command: what any robot's drivers speak
(the physics server is one implementation, a real arm's driver and camera another).

| channel | type | who publishes |
|---|---|---|
| SB_ROBOT_ARM_STATE | robot_arm_state_t | the arm's driver, every frame: arm joints, tool pose, the trajectory tracked |
| SB_ROBOT_OBJECTS | robot_objects_t | the camera's driver: every object seen, name and world pose |
| SB_ROBOT_ARM_CMD | robot_arm_cmd_t | the skills (skillbus.robot.arm), scripts: a timed joint trajectory |
| SB_ROBOT_CMD_REPLY | robot_cmd_reply_t | the arm's driver: each command accepted, or rejected with why |

Nothing here knows the simulator (docs/sim_server.md, "Robot interface").

>>> m = arm_command("up", ["joint2"], [(1.0, [0.3])])
>>> m.joint_names, m.points[0].time_from_start_ns, m.points[0].positions
(['joint2'], 1000000000, [0.3])
"""

from __future__ import annotations

from typing import Sequence

from skillbus.bus import channel
from skillbus.msgs import joint_traj_point_t, robot_arm_cmd_t
from skillbus.validate import BadValue, finite, finite_all, integer, pose, text

# Bounds of what a robot's drivers can report; far outside any arm and workspace, so a
# value beyond them is a corrupt or forged message, not a measurement.
MAX_JOINTS = 64               # joints of one arm
MAX_JOINT_POSITION = 100.0    # rad (m for prismatic joints): 16 turns
MAX_JOINT_VELOCITY = 1_000.0  # rad/s
MAX_JOINT_EFFORT = 1e6        # N m (N)
REACH_M = 100.0               # a pose's distance from the world origin on each axis


def arm_state_channel() -> str:
    return channel("SB_ROBOT_ARM_STATE")


def arm_cmd_channel() -> str:
    return channel("SB_ROBOT_ARM_CMD")


def reply_channel() -> str:
    return channel("SB_ROBOT_CMD_REPLY")


def objects_channel() -> str:
    return channel("SB_ROBOT_OBJECTS")


def traj_point(t: float, positions: Sequence[float], velocities: Sequence[float] = ()) -> joint_traj_point_t:
    """A trajectory point due `t` seconds after the command's start (without velocities the
    follower derives them)."""
    p = joint_traj_point_t()
    p.time_from_start_ns = int(round(t * 1e9))
    p.positions = [float(x) for x in positions]
    p.num_positions = len(p.positions)
    p.velocities = [float(x) for x in velocities]
    p.num_velocities = len(p.velocities)
    return p


def arm_command(cmd_id: str, joints: Sequence[str],
                points: Sequence[tuple[float, Sequence[float]] | joint_traj_point_t]) -> robot_arm_cmd_t:
    """A timed joint trajectory: points are (seconds from start, positions) or ready
    joint_traj_point_t. A single point at 0 s is a position target timed by the velocity
    limits."""
    m = robot_arm_cmd_t()
    m.id = cmd_id
    m.joint_names = list(joints)
    m.num_joints = len(m.joint_names)
    m.points = [p if isinstance(p, joint_traj_point_t) else traj_point(p[0], p[1]) for p in points]
    m.num_points = len(m.points)
    return m


def check_arm_state(s) -> None:
    """Raises BadValue unless the robot_arm_state_t `s` is one to act on: 1 to MAX_JOINTS
    named joints (distinct names, one position, velocity and effort each), every number
    finite and within the bounds above, the tool pose a pose (a unit quaternion), the
    tracking error not negative. Skills plan from these positions and decide "settled"
    from the tracking error: a NaN there never compares below a tolerance."""
    n = integer(s.num_joints, "num_joints", 1, MAX_JOINTS)
    names = list(s.joint_names)
    if not all(type(x) is str and x for x in names):  # (named one by one only when one is bad)
        names = [text(x, f"joint_names[{i}]") for i, x in enumerate(names)]
    if len(names) != n or len(set(names)) != n:
        raise BadValue("joint_names", names, f"{n} distinct names expected")
    finite_all(s.position, "position", -MAX_JOINT_POSITION, MAX_JOINT_POSITION, length=n)
    finite_all(s.velocity, "velocity", -MAX_JOINT_VELOCITY, MAX_JOINT_VELOCITY, length=n)
    finite_all(s.effort, "effort", -MAX_JOINT_EFFORT, MAX_JOINT_EFFORT, length=n)
    pose(s.tool_pose, "tool_pose", REACH_M)
    finite(s.arm_tracking_error, "arm_tracking_error", 0.0, MAX_JOINT_POSITION)


def check_objects(m) -> None:
    """Raises BadValue unless every object of the robot_objects_t `m` has a name and a
    pose (REACH_M, a unit quaternion): Locate writes these poses into the world model."""
    integer(m.num_objects, "num_objects", len(m.objects), len(m.objects))
    for i, o in enumerate(m.objects):
        text(o.name, f"objects[{i}].name")
        pose(o.pose, f"objects[{i}].pose", REACH_M)
