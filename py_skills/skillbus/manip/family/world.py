"""World-model writes of the family's skills: what a pick, a place or an articulation
skill changed, as one transaction each (skillbus.world.poses keeps a containment and the
pose relative to it together)."""

from __future__ import annotations

from typing import Any

from skillbus.msgs import wm_op_t
from skillbus.world.convert import op
from skillbus.world.poses import reparent_ops, world_pose_op


def world_of(view: Any, name: str) -> tuple[tuple, tuple]:
    """An object's world pose (x y z, qx qy qz qw) now, from the task view."""
    p, q = view.object_pose(name)
    wp, wq = view_to_world(view, p, q)
    return wp, wq


def view_to_world(view: Any, p: Any, q: Any) -> tuple[tuple, tuple]:
    from skillbus.manip.frames import to_world
    return to_world(view.base, p, q)


def contained_ops(wmi: Any, obj: str, parent: str, obj_world: tuple, parent_world: tuple | None = None) -> list:
    """`parent` contains `obj` at `obj_world`; `parent_world`: the parent's world pose when
    the same transaction writes it (a gripper at the tool's pose)."""
    ops = []
    if parent_world is not None:
        ops.append(world_pose_op(wmi, parent, *parent_world))
    return ops + reparent_ops(wmi, obj, parent, world=obj_world, parent_pose=parent_world)


def joint_position_op(wmi: Any, eid: str, position: float) -> wm_op_t:
    e = wmi.get_element(eid)
    e.setProperty("skiros:JointPosition", round(float(position), 6), "xsd:float")
    return op(wm_op_t.UPDATE_ELEMENT, element=e)


def shows_contained(wmi: Any, parent: str, obj: str) -> bool:
    return bool(wmi.get_relations(parent, "skiros:contain", obj))


def shows_joint(wmi: Any, eid: str, position: float) -> bool:
    e = wmi.get_element(eid)
    if not e.hasProperty("skiros:JointPosition", not_none=True):
        return False
    return abs(float(e.getProperty("skiros:JointPosition").value) - round(float(position), 6)) < 1e-5
