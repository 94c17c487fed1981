"""Poses the family's skills build, in the arm's base frame with quaternions as w x y z
(numpy arrays, as InternDataEngine's skills use).

>>> q = top_down(0.0); [round(float(x), 6) for x in q]
[0.0, 0.0, 1.0, 0.0]
>>> p, q = rotate_about([1, 0, 0], [0, 0, 1], [0, 0, 0], math.pi / 2, top_down(0.0))
>>> [round(float(x), 6) for x in p]
[0.0, 1.0, 0.0]
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from skillbus.manip.frames import wxyz_to_xyzw, xyzw_to_wxyz
from skillbus.quat import qmul, yaw_of

DOWN_XYZW = (0.0, 1.0, 0.0, 0.0)  # the tool's z pointing down: half a turn about y


def axis_angle(axis: Sequence[float], angle: float) -> tuple[float, float, float, float]:
    """x y z w."""
    a = np.asarray(axis, dtype=float)
    a = a / (np.linalg.norm(a) or 1.0)
    s = math.sin(angle / 2)
    return (float(a[0] * s), float(a[1] * s), float(a[2] * s), math.cos(angle / 2))


def top_down(yaw: float) -> np.ndarray:
    """The tool pointing down, turned by `yaw` about the vertical (w x y z)."""
    return np.array(xyzw_to_wxyz(qmul(axis_angle((0, 0, 1), yaw), DOWN_XYZW)))


def fold(yaw: float) -> float:
    """The yaw within [-45, 45] degrees that grasps a square the same way."""
    return (yaw + math.pi / 4) % (math.pi / 2) - math.pi / 4


def yaw_wxyz(q: Sequence[float]) -> float:
    return yaw_of(wxyz_to_xyzw(q))


def turn(q_wxyz: Sequence[float], axis: Sequence[float], angle: float) -> np.ndarray:
    """The orientation rotated by `angle` about the (base-frame) `axis`."""
    return np.array(xyzw_to_wxyz(qmul(axis_angle(axis, angle), wxyz_to_xyzw(q_wxyz))))


def rotate_about(p: Sequence[float], axis: Sequence[float], origin: Sequence[float], angle: float,
                 q_wxyz: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """A pose carried by a rotation of `angle` about the line through `origin` along
    `axis` (a door's handle as the door turns)."""
    from skillbus.quat import rotate
    d = np.asarray(p, dtype=float) - np.asarray(origin, dtype=float)
    r = np.array(rotate(axis_angle(axis, angle), d)) + np.asarray(origin, dtype=float)
    return r, turn(q_wxyz, axis, angle)


def compose(frame: tuple[Sequence[float], Sequence[float]], local: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """A pose given as [x y z qw qx qy qz] in `frame` (p, q w x y z) in the frame's frame."""
    from skillbus.quat import rotate
    fp, fq = frame
    lq = wxyz_to_xyzw(local[3:7])
    p = np.array(rotate(wxyz_to_xyzw(fq), local[:3])) + np.asarray(fp, dtype=float)
    return p, np.array(xyzw_to_wxyz(qmul(wxyz_to_xyzw(fq), lq)))


def pose7(value: Sequence[float], what: str) -> tuple[np.ndarray, np.ndarray]:
    """[x y z qw qx qy qz] from a configuration value; ValueError naming `what`."""
    try:
        v = [float(x) for x in value]
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be 7 numbers [x, y, z, qw, qx, qy, qz], not {value!r}") from None
    if len(v) != 7 or not all(math.isfinite(x) for x in v):
        raise ValueError(f"{what} must be 7 finite numbers [x, y, z, qw, qx, qy, qz], not {value!r}")
    q = np.array(v[3:])
    n = np.linalg.norm(q)
    if n < 1e-9:
        raise ValueError(f"{what} has a zero quaternion")
    return np.array(v[:3]), q / n
