"""Poses of world-model elements computed from a client's replica (no server call, so a
skill under lockstep gets the same answer on every run).

An element's pose (skiros:PositionX/Y/Z, OrientationX/Y/Z/W; missing = identity) is
relative to the element that contains it (skiros:contain), as the world model keeps it
(docs/world_model.md); the chain ends at an element nobody contains (the scene: world).
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


def set_world_pose(wmi: Any, eid: str, p: Vec, q: Quat, parent: str | None = None) -> None:
    """Writes the pose of `eid` given in the world frame, relative to its container (or
    to `parent`, when the containment is being written in the same breath)."""
    parent = parent or parent_of(wmi, eid)
    if parent is not None:
        pp, pq = world_pose(wmi, parent)
        d = rotate(qconj(pq), (p[0] - pp[0], p[1] - pp[1], p[2] - pp[2]))
        q = qmul(qconj(pq), q)
        p = d
    e = wmi.get_element(eid)
    for k, v in zip(POS + ORI, tuple(p) + tuple(q)):
        e.setProperty(k, round(float(v), 6), "xsd:float")
    wmi.write([op(wm_op_t.UPDATE_ELEMENT, element=e)])
