"""What the console's 3D view draws: the scene's bodies as boxes, cylinders and spheres
(from its scene file and URDFs), and each frame's poses of them from the physics
server's state (sim_state_t): the arm's links by forward kinematics of its joints, the
objects as the physics has them, the fixtures where the scene puts them.

The browser gets the shapes once (:meth:`Scene3D.shapes`) and then, per frame, a pose
(x y z qx qy qz qw) per body (:meth:`Scene3D.poses`): it draws no kinematics itself.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

COLORS = {"robot": "#8a9bb0", "fixture": "#c8b08a", "obstacle": "#b06060", "object": "#4a90d9"}
OBJECT_COLORS = {"red": "#d64541", "green": "#3fa34d", "blue": "#3b6fd4", "yellow": "#e0c23c"}


def rpy_matrix(r: float, p: float, y: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def transform(xyz=(0.0, 0.0, 0.0), rot: np.ndarray | None = None) -> np.ndarray:
    t = np.eye(4)
    t[:3, 3] = xyz
    if rot is not None:
        t[:3, :3] = rot
    return t


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    a = axis / (np.linalg.norm(axis) or 1.0)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * (k @ k)


def quat_matrix(q) -> np.ndarray:
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def pose_matrix(pose) -> np.ndarray:
    return transform(pose[:3], quat_matrix(pose[3:7]))


def matrix_pose(t: np.ndarray) -> list[float]:
    """4x4 -> [x y z qx qy qz qw]."""
    m = t[:3, :3]
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        q = [(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s]
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2]) * 2
        q = [0.25 * s, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s]
    elif m[1, 1] > m[2, 2]:
        s = math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2]) * 2
        q = [(m[0, 1] + m[1, 0]) / s, 0.25 * s, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s]
    else:
        s = math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1]) * 2
        q = [(m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, 0.25 * s, (m[1, 0] - m[0, 1]) / s]
    return [round(float(v), 6) for v in list(t[:3, 3]) + q]


@dataclass
class Joint:
    name: str
    kind: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray


@dataclass
class Urdf:
    """The links' shapes and the joints of one URDF (primitive shapes only; a mesh is
    drawn as its bounding box if the URDF gives none: skipped)."""
    links: dict[str, list[dict[str, Any]]] = field(default_factory=dict)
    joints: list[Joint] = field(default_factory=list)

    @classmethod
    def load(cls, path: Path) -> "Urdf":
        root = ET.parse(path).getroot()
        out = cls()
        for link in root.findall("link"):
            shapes = []
            parts = link.findall("visual") or link.findall("collision")
            for part in parts:
                geo = part.find("geometry")
                if geo is None:
                    continue
                origin = _origin(part.find("origin"))
                for kind in ("box", "cylinder", "sphere"):
                    g = geo.find(kind)
                    if g is None:
                        continue
                    if kind == "box":
                        size = [float(v) for v in g.get("size", "0 0 0").split()]
                    elif kind == "cylinder":
                        size = [float(g.get("radius", 0)), float(g.get("length", 0))]
                    else:
                        size = [float(g.get("radius", 0))]
                    shapes.append({"kind": kind, "size": size, "origin": matrix_pose(origin)})
            out.links[link.get("name")] = shapes
        for j in root.findall("joint"):
            axis = j.find("axis")
            out.joints.append(Joint(j.get("name"), j.get("type", "fixed"), j.find("parent").get("link"),
                                    j.find("child").get("link"), _origin(j.find("origin")),
                                    np.array([float(v) for v in (axis.get("xyz") if axis is not None else "1 0 0").split()])))
        return out

    def root(self) -> str:
        children = {j.child for j in self.joints}
        return next(n for n in self.links if n not in children)

    def link_poses(self, base: np.ndarray, q: dict[str, float]) -> dict[str, np.ndarray]:
        """Each link's world transform for joint positions `q` (missing joints: 0)."""
        out = {self.root(): base}
        pending = list(self.joints)
        while pending:
            rest = []
            for j in pending:
                if j.parent not in out:
                    rest.append(j)
                    continue
                t = out[j.parent] @ j.origin
                v = q.get(j.name, 0.0)
                if j.kind in ("revolute", "continuous"):
                    t = t @ transform(rot=axis_angle(j.axis, v))
                elif j.kind == "prismatic":
                    t = t @ transform(j.axis * v)
                out[j.child] = t
            if len(rest) == len(pending):
                break  # (links not connected to the root are not drawn)
            pending = rest
        return out


def _origin(o) -> np.ndarray:
    if o is None:
        return np.eye(4)
    xyz = [float(v) for v in o.get("xyz", "0 0 0").split()]
    rpy = [float(v) for v in o.get("rpy", "0 0 0").split()]
    return transform(xyz, rpy_matrix(*rpy))


class Scene3D:
    """One scene file's bodies; body names: "<robot>/<link>", "<fixture>/<link>", objects by name."""

    def __init__(self, scene_file: Path) -> None:
        self.path = Path(scene_file)
        spec = json.loads(self.path.read_text())
        base = self.path.parent
        self.robots: list[tuple[str, Urdf, np.ndarray]] = []
        robots = spec.get("robots") or ([spec["robot"]] if "robot" in spec else [])
        for r in robots:
            self.robots.append((r.get("name", "robot"), Urdf.load(base / r["urdf"]),
                                pose_matrix(r.get("pose", [0, 0, 0, 0, 0, 0, 1]))))
        self.static: dict[str, tuple[dict, np.ndarray, str]] = {}  # body -> (shapes, world pose, role)
        self._shapes: list[dict[str, Any]] = []
        for role, items in (("fixture", spec.get("fixtures", [])), ("obstacle", spec.get("obstacles", []))):
            for f in items:
                urdf = Urdf.load(base / f["urdf"])
                for link, t in urdf.link_poses(pose_matrix(f.get("pose", [0, 0, 0, 0, 0, 0, 1])), {}).items():
                    name = f"{f['name']}/{link}"
                    self._shapes.append({"body": name, "role": role, "color": COLORS[role],
                                         "shapes": urdf.links.get(link, []), "pose": matrix_pose(t)})
        for name, urdf, _ in self.robots:
            for link, shapes in urdf.links.items():
                self._shapes.append({"body": f"{name}/{link}", "role": "robot", "color": COLORS["robot"],
                                     "shapes": shapes})
        self.objects = {o["name"]: o for o in spec.get("objects", [])}
        for o in spec.get("objects", []):
            size = o.get("size", [0.05, 0.05, 0.05])
            kind = o.get("shape", "box")
            self._shapes.append({"body": o["name"], "role": "object",
                                 "color": OBJECT_COLORS.get(o["name"], COLORS["object"]),
                                 "shapes": [{"kind": kind if kind in ("box", "cylinder", "sphere") else "box",
                                             "size": size, "origin": [0, 0, 0, 0, 0, 0, 1]}]})

    def shapes(self) -> list[dict[str, Any]]:
        """Every body with its shapes (in its own frame), colour and role; fixtures and
        obstacles with their (fixed) pose."""
        return self._shapes

    def poses(self, joints: dict[str, float], objects: dict[str, list[float]], robot: int = 0) -> dict[str, list[float]]:
        """The moving bodies' poses: robot `robot`'s links for `joints`, and `objects`."""
        out: dict[str, list[float]] = {}
        if robot < len(self.robots):
            name, urdf, base = self.robots[robot]
            for link, t in urdf.link_poses(base, joints).items():
                out[f"{name}/{link}"] = matrix_pose(t)
        out.update({k: [round(float(v), 6) for v in p] for k, p in objects.items()})
        return out

    def tool_path(self, joint_names: list[str], points: list[list[float]], tool_link: str | None = None,
                  robot: int = 0) -> list[list[float]]:
        """Where a joint trajectory takes the tool link: one xyz per point."""
        if robot >= len(self.robots):
            return []
        name, urdf, base = self.robots[robot]
        link = tool_link or _last_link(urdf)
        path = []
        for p in points:
            if not finite(p):
                return []  # (a command no arm would play)
            t = urdf.link_poses(base, dict(zip(joint_names, p))).get(link)
            if t is not None:
                path.append([round(float(v), 4) for v in t[:3, 3]])
        return path


def _last_link(urdf: Urdf) -> str:
    """The arm's end: the deepest link reached by revolute joints."""
    rev = [j for j in urdf.joints if j.kind in ("revolute", "continuous")]
    return rev[-1].child if rev else urdf.root()


def finite(values) -> bool:
    return all(math.isfinite(v) for v in values)


def sim_state_view(s) -> tuple[dict[str, float], dict[str, list[float]], list[dict[str, Any]]]:
    """A sim_state_t as (joint positions, object poses, contacts); ValueError for one that
    cannot be drawn (a joint or pose that is not a finite number: no physics sends it)."""
    if not finite(s.position) or not all(finite(o.pose) for o in s.objects) or \
            not all(math.isfinite(c.normal_force) for c in s.contacts):
        raise ValueError("a physics state with a value that is not a finite number")
    joints = dict(zip(s.joint_names, s.position))
    objects = {o.name: list(o.pose) for o in s.objects}
    contacts = [{"a": c.body_a, "b": c.body_b, "points": c.points, "force": round(c.normal_force, 3)}
                for c in s.contacts]
    return joints, objects, contacts
