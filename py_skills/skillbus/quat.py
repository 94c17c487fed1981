"""Quaternions (x y z w) and poses (x y z qx qy qz qw) in plain Python: what the scene
files, the world-model poses and the benchmarks need, without a numeric library."""

from __future__ import annotations

import math
from typing import Sequence

Vec = tuple[float, float, float]
Quat = tuple[float, float, float, float]


def qmul(a: Quat, b: Quat) -> Quat:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def qconj(q: Quat) -> Quat:
    return (-q[0], -q[1], -q[2], q[3])


def rotate(q: Quat, v: Sequence[float]) -> Vec:
    x, y, z, _ = qmul(qmul(q, (v[0], v[1], v[2], 0.0)), qconj(q))
    return (x, y, z)


def yaw_of(q: Quat) -> float:
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def relative(parent: Sequence[float], child: Sequence[float]) -> tuple[Vec, Quat]:
    """The child's pose in the parent's frame (both given in the same frame)."""
    pq: Quat = tuple(parent[3:7])  # type: ignore[assignment]
    p = rotate(qconj(pq), (child[0] - parent[0], child[1] - parent[1], child[2] - parent[2]))
    return p, qmul(qconj(pq), tuple(child[3:7]))  # type: ignore[arg-type]
