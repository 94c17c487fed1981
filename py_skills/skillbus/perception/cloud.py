"""A depth camera's capture, put back together from its camera_cloud_t parts.

The physics server (or a real camera's driver) publishes one capture as parts split by
rows (lcmtypes/camera_cloud_t.lcm). `CloudAssembler` takes parts in any order, checks that
they agree with each other, and gives a `Cloud` when the last one is in: an organized
cloud (height x width x 3, float32, camera's optical frame, NaN where a pixel had no
return) with the camera's pose, so `world_points()` gives the returns in the world frame.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from skillbus.msgs import camera_cloud_t

POINT_DTYPE = np.dtype("<f4")  # little-endian float32, as the message says


class CloudError(ValueError):
    """A part that cannot belong to a capture (says which field)."""


@dataclasses.dataclass
class Cloud:
    camera: str
    capture: int
    request_id: str
    width: int
    height: int
    intrinsics: tuple[float, float, float, float]  # fx fy cx cy
    range_m: tuple[float, float]  # near far (m along a ray)
    pose: tuple[float, ...]  # the optical frame in the world: x y z qx qy qz qw
    points: np.ndarray  # (height, width, 3) float32, optical frame, NaN: no return
    on_robot: np.ndarray  # (height, width) bool: the return is on a robot (the self filter)
    frame: int = -1  # the lockstep frame it was published in

    @property
    def returns(self) -> int:
        return int(np.count_nonzero(~np.isnan(self.points[..., 2])))

    def rotation(self) -> np.ndarray:
        x, y, z, w = self.pose[3:7]
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])

    def world_points(self, robot: bool = True) -> np.ndarray:
        """(N, 3) float64: every return in the world frame, row-major pixel order (without
        the robot's returns when `robot` is False)."""
        p = self.points.reshape(-1, 3).astype(np.float64)
        keep = ~np.isnan(p[:, 2])
        if not robot:
            keep &= ~self.on_robot.reshape(-1)
        p = p[keep]
        return p @ self.rotation().T + np.asarray(self.pose[:3])

    def write_ply(self, path: str | Path) -> None:
        """The returns in the world frame as an ASCII PLY (opens in MeshLab, CloudCompare)."""
        pts = self.world_points()
        with open(path, "w") as f:
            f.write(f"ply\nformat ascii 1.0\ncomment skillbus camera {self.camera} capture {self.capture}\n"
                    f"element vertex {len(pts)}\nproperty float x\nproperty float y\nproperty float z\nend_header\n")
            for x, y, z in pts:
                f.write(f"{x:.6f} {y:.6f} {z:.6f}\n")


def _check_part(m: camera_cloud_t) -> None:
    if m.error:
        return
    if not (0 < m.width <= 1 << 20 and 0 < m.height <= 1 << 20):
        raise CloudError(f"width {m.width} x height {m.height} is no image size")
    if not (0 <= m.part < m.num_parts <= m.height):
        raise CloudError(f"part {m.part} of {m.num_parts} (height {m.height})")
    if not (0 <= m.row_start and 0 < m.num_rows and m.row_start + m.num_rows <= m.height):
        raise CloudError(f"rows {m.row_start}..{m.row_start + m.num_rows - 1} of a {m.height}-row image")
    if m.num_bytes != m.num_rows * m.width * 12 or len(m.points) != m.num_bytes:
        raise CloudError(f"{len(m.points)} bytes of points for {m.num_rows} rows of {m.width} (12 bytes a point)")
    if m.num_mask_bytes != (m.num_rows * m.width + 7) // 8 or len(m.robot_mask) != m.num_mask_bytes:
        raise CloudError(f"{len(m.robot_mask)} bytes of robot mask for {m.num_rows} rows of {m.width} (a bit a pixel)")
    if not all(math.isfinite(v) for v in (*m.intrinsics, *m.pose, *m.range)) or m.intrinsics[0] <= 0 or \
            m.intrinsics[1] <= 0:
        raise CloudError("intrinsics, range or pose not finite (or a focal length <= 0)")
    if not 0 < m.range[0] < m.range[1]:
        raise CloudError(f"range {m.range[0]}..{m.range[1]} m is not 0 < near < far")


class CloudAssembler:
    """Collects the parts of captures; `add` returns the Cloud its last part completes.

    A capture is keyed by (camera, capture). Parts that disagree with the first one of
    their capture (size, pose, number of parts) or overlap are refused with CloudError;
    `keep` bounds how many incomplete captures are held (the oldest goes first)."""

    def __init__(self, keep: int = 8) -> None:
        self.keep = keep
        self._open: dict[tuple[str, int], dict[int, camera_cloud_t]] = {}

    def add(self, m: camera_cloud_t, frame: int = -1) -> Cloud | None:
        _check_part(m)
        key = (m.camera, m.capture)
        parts = self._open.setdefault(key, {})
        if parts:
            first = next(iter(parts.values()))
            same = (first.width, first.height, first.num_parts, tuple(first.pose), first.request_id) == \
                (m.width, m.height, m.num_parts, tuple(m.pose), m.request_id)
            if not same:
                del self._open[key]
                raise CloudError(f"part {m.part} of capture {m.capture} of camera {m.camera} does not match its "
                                 "other parts")
        parts[m.part] = m
        while len(self._open) > self.keep:
            del self._open[next(iter(self._open))]
        if len(parts) < m.num_parts:
            return None
        del self._open[key]
        ordered = [parts[i] for i in range(m.num_parts)]
        rows = 0
        for p in ordered:
            if p.row_start != rows:
                raise CloudError(f"capture {m.capture} of camera {m.camera}: part {p.part} starts at row "
                                 f"{p.row_start}, not {rows}")
            rows += p.num_rows
        if rows != m.height:
            raise CloudError(f"capture {m.capture} of camera {m.camera}: its parts hold {rows} of {m.height} rows")
        data = b"".join(p.points for p in ordered)
        points = np.frombuffer(data, dtype=POINT_DTYPE).reshape(m.height, m.width, 3)
        mask = np.concatenate([np.unpackbits(np.frombuffer(p.robot_mask, dtype=np.uint8), bitorder="little")
                               [:p.num_rows * p.width] for p in ordered]).astype(bool).reshape(m.height, m.width)
        return Cloud(m.camera, m.capture, m.request_id, m.width, m.height, tuple(m.intrinsics), tuple(m.range),
                     tuple(m.pose), points, mask, frame)
