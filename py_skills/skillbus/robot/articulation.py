"""The articulated objects of a skill process's world (``skills-process --interface
articulation=skillbus.robot.articulation``): each annotated joint of each articulated
object (a cabinet's drawer and door), its position, limits, axis and handle grasp, as the
robot's perception reports them (articulation_state_t on SB_ROBOT_ARTICULATION, world
frame). The physics server publishes a perfect reading every frame of a scene with
articulated objects; on a real robot an articulation tracker would.

Under lockstep the reading is a lockstep subscription (a tick of frame n sees frame n);
on the wall clock it comes straight over the bus. The latest message is decoded only
when a skill asks.
"""

from __future__ import annotations

from typing import Any

from skillbus.bus import Bus, channel
from skillbus.msgs import articulated_joint_t, articulation_state_t
from skillbus.robot.latest import LatestReading
from skillbus.validate import finite, finite_all, integer, one_of, pose, text

REACH_M = 100.0


class ArticulationError(RuntimeError):
    pass


def articulation_channel() -> str:
    return channel("SB_ROBOT_ARTICULATION")


def check_articulation(m: articulation_state_t) -> None:
    """Raises BadValue unless every joint has names, a kind, finite numbers within its
    limits' order, a unit axis and, with a handle, a sane pose."""
    integer(m.num_joints, "num_joints", len(m.joints), len(m.joints))
    for i, j in enumerate(m.joints):
        text(j.object, f"joints[{i}].object")
        text(j.joint, f"joints[{i}].joint")
        one_of(j.kind, f"joints[{i}].kind", ("prismatic", "revolute"))
        finite(j.position, f"joints[{i}].position")
        finite(j.velocity, f"joints[{i}].velocity")
        lo = finite(j.lower, f"joints[{i}].lower")
        finite(j.upper, f"joints[{i}].upper", lo=lo)
        finite_all(j.axis, f"joints[{i}].axis", -1.0001, 1.0001)
        finite_all(j.origin, f"joints[{i}].origin", -REACH_M, REACH_M)
        if j.has_handle:
            pose(j.handle_pose, f"joints[{i}].handle_pose", REACH_M)


class Articulation(LatestReading[articulation_state_t]):
    def __init__(self, bus: Bus, participant: Any = None) -> None:
        super().__init__(bus, participant, articulation_channel(), articulation_state_t, check_articulation,
                         "articulation")

    def joints(self) -> list[articulated_joint_t]:
        m = self.latest
        if m is None:
            raise ArticulationError(f"no articulated objects reported yet on {articulation_channel()} (does the "
                                    "scene have any, and is the physics server running?)")
        return list(m.joints)


def interface(bus: Bus, participant: Any = None, arg: str = "", **options: Any) -> Articulation:
    """The articulation interface (skillbus.robot.interfaces). `arg` is unused."""
    return Articulation(bus, participant)
