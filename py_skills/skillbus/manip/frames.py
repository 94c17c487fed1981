"""Poses between the world frame (the bus's x y z qx qy qz qw) and the arm's base frame
(InternDataEngine's p, q with q as w x y z).

>>> base = ((1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
>>> to_world(base, (0.5, 0.0, 0.2), (0.0, 1.0, 0.0, 0.0))
((1.5, 0.0, 0.2), (1.0, 0.0, 0.0, 0.0))
>>> p, q = to_base(base, (1.5, 0.0, 0.2), (1.0, 0.0, 0.0, 0.0))
>>> tuple(round(x, 9) for x in p), q
((0.5, 0.0, 0.2), (0.0, 1.0, 0.0, 0.0))
"""

from __future__ import annotations

import math
from typing import Sequence

from skillbus.quat import qmul, rotate

Vec3 = tuple[float, float, float]
Pose = tuple[Vec3, tuple[float, float, float, float]]  # position, quaternion x y z w


def wxyz_to_xyzw(q: Sequence[float]) -> tuple[float, float, float, float]:
    return (float(q[1]), float(q[2]), float(q[3]), float(q[0]))


def xyzw_to_wxyz(q: Sequence[float]) -> tuple[float, float, float, float]:
    return (float(q[3]), float(q[0]), float(q[1]), float(q[2]))


def _conj(q: Sequence[float]) -> tuple[float, float, float, float]:  # (quat.qconj, typed for any sequence)
    return (-q[0], -q[1], -q[2], q[3])


def to_world(base: Pose, p: Sequence[float], q_wxyz: Sequence[float]) -> Pose:
    """A base-frame pose (q as w x y z) in the world (q as x y z w)."""
    bp, bq = base
    r = rotate(bq, tuple(float(x) for x in p))
    return ((bp[0] + r[0], bp[1] + r[1], bp[2] + r[2]), tuple(qmul(bq, wxyz_to_xyzw(q_wxyz))))  # type: ignore


def to_base(base: Pose, p: Sequence[float], q_xyzw: Sequence[float]) -> tuple[Vec3, tuple[float, float, float, float]]:
    """A world pose (q as x y z w) in the base frame (q as w x y z)."""
    bp, bq = base
    inv = _conj(bq)
    d = rotate(inv, (p[0] - bp[0], p[1] - bp[1], p[2] - bp[2]))
    return (d[0], d[1], d[2]), xyzw_to_wxyz(qmul(inv, tuple(float(x) for x in q_xyzw)))


def angle_between(q1_wxyz: Sequence[float], q2_wxyz: Sequence[float]) -> float:
    """The rotation angle (rad) between two orientations."""
    dot = abs(sum(a * b for a, b in zip(q1_wxyz, q2_wxyz)))
    return 2 * math.acos(min(1.0, dot))
