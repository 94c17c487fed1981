"""Objects on a support surface, from one organized cloud (docs/perception.md, "Finding
objects").

1. The support: the most common height of the returns (1 mm bins, refined by the median
   of the returns within 3 mm of it): a table top or a bin's floor seen from above.
2. The objects: returns between `min_height` and `max_height` over the support and over
   its footprint, split into connected regions of the image (4-neighbours).
3. Each region's top faces (its returns near its highest, apart in the image: objects side
   by side make one region, bridged by a side face seen at a slant, but two top faces), and
   each top face's outline in the image (pixels with a neighbour off the face). A
   rectangle is fitted to the outline:
   the smallest-area rectangle around the face first, then least squares of the outline's
   distances to the rectangle's sides (centre, yaw and half sizes), which averages out the
   pixel staircase of a slanted edge.
4. The box: that rectangle, from the support up to the top face.

Everything is numpy on one cloud and visits pixels in row-major order: the same cloud
gives the same detections, bit for bit.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque

import numpy as np

from skillbus.perception.cloud import Cloud


@dataclasses.dataclass
class Detection:
    position: tuple[float, float, float]  # the box's centre, world frame
    yaw: float                            # rad about world z; a box's length lies along it
    size: tuple[float, float, float]      # length, width, height (m)
    points: int                           # returns on the object

    def quaternion(self) -> tuple[float, float, float, float]:
        """x y z w: the yaw about z."""
        return (0.0, 0.0, math.sin(self.yaw / 2), math.cos(self.yaw / 2))


@dataclasses.dataclass
class Scene:
    support_z: float
    detections: list[Detection]


class SegmentError(ValueError):
    pass


def world_grid(cloud: Cloud) -> np.ndarray:
    """(height, width, 3) float64: every pixel's point in the world frame (NaN: no return)."""
    p = cloud.points.astype(np.float64)
    return p @ cloud.rotation().T + np.asarray(cloud.pose[:3])


def support_height(z: np.ndarray) -> float:
    """The most common height among `z` (finite values), to a fraction of a millimetre."""
    if z.size == 0:
        raise SegmentError("no returns to find a support surface in")
    bins = np.floor(z / 0.001).astype(np.int64)
    values, counts = np.unique(bins, return_counts=True)
    mode = (values[np.argmax(counts)] + 0.5) * 0.001  # (np.unique sorts: the lowest of equal counts)
    near = z[np.abs(z - mode) <= 0.003]
    return float(np.median(near))


def _components(mask: np.ndarray) -> list[np.ndarray]:
    """Connected regions (4-neighbours) of a boolean image, as arrays of (row, col), in
    the row-major order of their first pixel."""
    seen = np.zeros_like(mask, dtype=bool)
    h, w = mask.shape
    out = []
    for r0, c0 in zip(*np.nonzero(mask)):
        if seen[r0, c0]:
            continue
        seen[r0, c0] = True
        q, region = deque([(r0, c0)]), []
        while q:
            r, c = q.popleft()
            region.append((r, c))
            for rr, cc in ((r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)):
                if 0 <= rr < h and 0 <= cc < w and mask[rr, cc] and not seen[rr, cc]:
                    seen[rr, cc] = True
                    q.append((rr, cc))
        out.append(np.array(region, dtype=np.int64))
    return out


def _hull(xy: np.ndarray) -> np.ndarray:
    """Convex hull (Andrew's monotone chain), counter-clockwise."""
    pts = np.unique(xy, axis=0)
    if len(pts) < 3:
        return pts

    def half(points):
        h: list = []
        for p in points:
            while len(h) >= 2 and np.cross(h[-1] - h[-2], p - h[-2]) <= 0:
                h.pop()
            h.append(p)
        return h

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def _min_area_rect(xy: np.ndarray) -> tuple[np.ndarray, float, float, float]:
    """(centre, yaw, half length, half width) of the smallest rectangle around the points."""
    hull = _hull(xy)
    best = None
    for i in range(len(hull)):
        e = hull[(i + 1) % len(hull)] - hull[i]
        n = math.hypot(*e)
        if n < 1e-12:
            continue
        yaw = math.atan2(e[1], e[0])
        c, s = math.cos(yaw), math.sin(yaw)
        u = hull @ np.array([c, s])
        v = hull @ np.array([-s, c])
        area = (u.max() - u.min()) * (v.max() - v.min())
        if best is None or area < best[0] - 1e-15:
            cu, cv = (u.max() + u.min()) / 2, (v.max() + v.min()) / 2
            best = (area, np.array([cu * c - cv * s, cu * s + cv * c]), yaw, (u.max() - u.min()) / 2,
                    (v.max() - v.min()) / 2)
    if best is None:
        return xy.mean(axis=0), 0.0, 0.0, 0.0
    return best[1], best[2], best[3], best[4]


def _fit_rect(edge: np.ndarray, centre: np.ndarray, yaw: float, a: float, b: float, iterations: int = 12):
    """Least squares of the outline points' distances to the rectangle's nearest sides
    over (cx, cy, yaw, a, b), from the smallest-area rectangle (Gauss-Newton)."""
    x = np.array([centre[0], centre[1], yaw, a, b], dtype=np.float64)
    for _ in range(iterations):
        c, s = math.cos(x[2]), math.sin(x[2])
        d = edge - x[:2]
        u = d[:, 0] * c + d[:, 1] * s
        v = -d[:, 0] * s + d[:, 1] * c
        on_u = np.abs(u) / max(x[3], 1e-9) >= np.abs(v) / max(x[4], 1e-9)  # nearer a side across u
        su, sv = np.sign(u), np.sign(v)
        r = np.where(on_u, np.abs(u) - x[3], np.abs(v) - x[4])
        # d|u|/d(cx, cy, yaw) = su * (-c, -s, v); d|v|/d(...) = sv * (s, -c, -u)
        J = np.zeros((len(edge), 5))
        J[:, 0] = np.where(on_u, -su * c, sv * s)
        J[:, 1] = np.where(on_u, -su * s, -sv * c)
        J[:, 2] = np.where(on_u, su * v, -sv * u)
        J[:, 3] = np.where(on_u, -1.0, 0.0)
        J[:, 4] = np.where(on_u, 0.0, -1.0)
        step, *_ = np.linalg.lstsq(J, -r, rcond=None)
        x += step
        if np.abs(step).max() < 1e-7:
            break
    return x[:2], float(x[2]), float(abs(x[3])), float(abs(x[4]))


def _normal_yaw(yaw: float, a: float, b: float) -> tuple[float, float, float]:
    """The length along the yaw; yaw in (-pi/2, pi/2], and for a square (sides within 10 %)
    in (-pi/4, pi/4] (a square's yaw is known only modulo a quarter turn)."""
    if b > a:
        a, b, yaw = b, a, yaw + math.pi / 2
    period = math.pi / 2 if a - b < 0.1 * a else math.pi
    yaw = math.remainder(yaw, period)
    if yaw <= -period / 2 + 1e-12:
        yaw += period
    return yaw, a, b


def detect(cloud: Cloud, *, min_height: float = 0.008, max_height: float = 0.3, min_points: int = 12,
           noise_m: float = 0.0, around: tuple[float, float] | None = None, radius: float = 0.35,
           sides: tuple[float, float] = (0.015, 0.15)) -> Scene:
    """The objects on the support surface the cloud sees most of (see the module's text).

    `around`: only returns within `radius` (m, in x and y) of this point count, for the
    support and the objects: one place of a scene (a table, a bin) when the camera sees
    several. `sides`: a found box whose footprint's sides are not within these (m) is not
    an object (a bin's wall, the edge of something under the view). `noise_m`: the
    camera's range noise (its standard deviation), which widens the tolerances."""
    grid = world_grid(cloud)
    valid = ~np.isnan(grid[..., 2]) & ~cloud.on_robot  # (the self filter: never an object, never the support)
    if around is not None:
        valid &= np.hypot(grid[..., 0] - around[0], grid[..., 1] - around[1]) <= radius
        if not valid.any():
            raise SegmentError(f"the camera sees nothing within {radius} m of ({around[0]:.3f}, {around[1]:.3f})")
    z = grid[..., 2]
    support = support_height(z[valid])
    tol = 0.003 + 3 * noise_m
    on_support = valid & (np.abs(z - support) <= tol)
    sx, sy = grid[on_support][:, 0], grid[on_support][:, 1]
    inside = valid & (grid[..., 0] >= sx.min()) & (grid[..., 0] <= sx.max()) & (grid[..., 1] >= sy.min()) & \
        (grid[..., 1] <= sy.max())
    above = inside & (z > support + max(min_height, tol)) & (z < support + max_height)
    # Pixel size on the object (m): for the outline's half-pixel inset.
    fx = cloud.intrinsics[0]
    out = []
    for region in _components(above):
        if len(region) < min_points:
            continue
        pts = grid[region[:, 0], region[:, 1]]
        zt = float(np.percentile(pts[:, 2], 90))
        face = pts[:, 2] >= zt - tol
        faces = np.zeros(above.shape, dtype=bool)
        faces[region[face, 0], region[face, 1]] = True
        # Objects side by side make one region (a side face seen at a slant bridges the gap
        # between them) but their top faces are apart: one object per top face.
        for top_face in _components(faces):
            if len(top_face) < min_points:
                continue
            d = _box(cloud, grid, above.shape, top_face, support, fx, sides)
            if d is not None:
                out.append(d)
    return Scene(support, out)


def _box(cloud: Cloud, grid: np.ndarray, shape: tuple, face_px: np.ndarray, support: float, fx: float,
         sides: tuple[float, float]) -> Detection | None:
    """The box under one top face (its pixels `face_px`), or None when it is no object."""
    rows, cols = face_px[:, 0], face_px[:, 1]
    top = float(np.median(grid[rows, cols, 2]))
    mask = np.zeros(shape, dtype=bool)
    mask[rows, cols] = True
    padded = np.pad(mask, 1)
    interior = padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:]
    edge_px = mask & ~interior
    edge = grid[edge_px][:, :2]
    face_xy = grid[rows, cols, :2]
    if len(face_xy) < 3 or len(edge) < 6:
        return None
    centre, yaw, a, b = _min_area_rect(face_xy)
    centre, yaw, a, b = _fit_rect(edge, centre, yaw, a, b)
    depth = float(np.median(cloud.points[rows, cols, 2]))
    half_pixel = 0.5 * depth / fx
    yaw, a, b = _normal_yaw(yaw, a + half_pixel, b + half_pixel)
    height = top - support
    if not (sides[0] <= 2 * b and 2 * a <= sides[1]):
        return None
    return Detection((float(centre[0]), float(centre[1]), support + height / 2), yaw, (2 * a, 2 * b, height),
                     int(len(face_px)))
