"""Poses of world-model elements computed from a client's replica (no server call, so a
skill under lockstep gets the same answer on every run).

An element's pose (skiros:PositionX/Y/Z, OrientationX/Y/Z/W; missing = identity) is
relative to the element that contains it (skiros:contain), as the world model keeps it
(docs/world_model.md); the chain ends at an element nobody contains (the scene: world).
So a containment change must re-express the pose in the new container, in the same
transaction: `reparent` (the grasp, the release, a located new object).
"""

from __future__ import annotations

import math
from typing import Any

from skillbus.msgs import wm_op_t
from skillbus.quat import Quat, Vec, qconj, qmul, rotate
from skillbus.world.convert import op

POS = ("skiros:PositionX", "skiros:PositionY", "skiros:PositionZ")
ORI = ("skiros:OrientationX", "skiros:OrientationY", "skiros:OrientationZ", "skiros:OrientationW")


def local_pose(e: Any) -> tuple[Vec, Quat]:
    def num(key: str, default: float) -> float:
        return float(e.getProperty(key).value) if e.hasProperty(key, not_none=True) else default
    p = tuple(num(k, 0.0) for k in POS)
    q = tuple(num(k, 0.0) for k in ORI[:3]) + (num(ORI[3], 1.0),)
    n = math.sqrt(sum(c * c for c in q)) or 1.0
    return p, tuple(c / n for c in q)  # type: ignore[return-value]


def parent_of(wmi: Any, eid: str) -> str | None:
    owners = [r["src"] for r in wmi.get_relations("", "skiros:contain", eid)]
    return owners[0] if owners else None


def world_pose(wmi: Any, eid: str) -> tuple[Vec, Quat]:
    chain, seen = [], set()
    cur: str | None = eid
    while cur is not None and cur not in seen:
        seen.add(cur)
        chain.append(cur)
        cur = parent_of(wmi, cur)
    p: Vec = (0.0, 0.0, 0.0)
    q: Quat = (0.0, 0.0, 0.0, 1.0)
    for e in reversed(chain):
        lp, lq = local_pose(wmi.get_element(e))
        r = rotate(q, lp)
        p = (p[0] + r[0], p[1] + r[1], p[2] + r[2])
        q = qmul(q, lq)
    return p, q


Pose = tuple[Vec, Quat]


def compose(a: Pose, b: Pose) -> Pose:
    """Pose `b` (given in frame `a`) in the frame `a` is given in."""
    r = rotate(a[1], b[0])
    return (a[0][0] + r[0], a[0][1] + r[1], a[0][2] + r[2]), qmul(a[1], b[1])


def in_frame(frame: Pose, pose: Pose) -> Pose:
    """`pose` (given in the same frame as `frame`) relative to `frame`."""
    pp, pq = frame
    p = pose[0]
    return rotate(qconj(pq), (p[0] - pp[0], p[1] - pp[1], p[2] - pp[2])), qmul(qconj(pq), pose[1])


def pose_op(wmi: Any, eid: str, local: Pose) -> wm_op_t:
    """The update that writes `local` (relative to the element's container) as the pose
    of `eid`, its other properties as the replica has them."""
    e = wmi.get_element(eid)
    for k, v in zip(POS + ORI, tuple(local[0]) + tuple(local[1])):
        e.setProperty(k, round(float(v), 6), "xsd:float")
    return op(wm_op_t.UPDATE_ELEMENT, element=e)


def world_pose_op(wmi: Any, eid: str, p: Vec, q: Quat, parent: str | None = None,
                  parent_pose: Pose | None = None) -> wm_op_t:
    """The update that puts `eid` at the world pose (p, q), relative to its container (or
    to `parent`); `parent_pose` is the container's world pose when it is being written in
    the same transaction (else it is read from the replica)."""
    parent = parent or parent_of(wmi, eid)
    if parent is not None:
        return pose_op(wmi, eid, in_frame(parent_pose or world_pose(wmi, parent), (p, q)))
    return pose_op(wmi, eid, (p, q))


def set_world_pose(wmi: Any, eid: str, p: Vec, q: Quat, parent: str | None = None) -> None:
    """Writes the pose of `eid` given in the world frame, relative to its container (or
    to `parent`, when the containment is being written in the same breath)."""
    wmi.write([world_pose_op(wmi, eid, p, q, parent)])


def reparent_ops(wmi: Any, eid: str, parent: str, world: Pose | None = None, parent_pose: Pose | None = None,
                 relation: str = "skiros:contain") -> list[wm_op_t]:
    """The operations that make `parent` the only container of `eid` and give `eid` its
    pose relative to `parent`: the world pose `world` when given (where it is now, as
    observed or as the robot carried it), else the world pose the world model has for it
    before the change (it stays where it is). Poses are relative to the container, so a
    containment change that leaves the old numbers would move the element to a phantom
    place: the relation and the pose go in one transaction, and no reader ever sees one
    without the other. `parent_pose`: the parent's world pose when the same transaction
    writes it."""
    world = world or world_pose(wmi, eid)
    old = [(r["src"], r["type"], r["dst"]) for r in wmi.get_relations("", relation, eid)]
    ops = [op(wm_op_t.REMOVE_RELATION, relation=r) for r in sorted(old) if r[0] != parent]
    if (parent, relation, eid) not in old:
        ops.append(op(wm_op_t.ADD_RELATION, relation=(parent, relation, eid)))
    ops.append(pose_op(wmi, eid, in_frame(parent_pose or world_pose(wmi, parent), world)))
    return ops


def reparent(wmi: Any, eid: str, parent: str, world: Pose | None = None) -> None:
    """Moves `eid` into `parent` (reparent_ops) in one write: committed at once, or under
    lockstep with this frame."""
    wmi.write(reparent_ops(wmi, eid, parent, world))
