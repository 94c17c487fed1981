"""Task-specific motions: move (a straight Cartesian offset), track (a path of
waypoints), approach_rotate (over an object, then the wrist turned to its yaw), flip
(an object picked, turned over and put down) and scan (the tool over an object from
several viewpoints, as a wrist camera would look)."""

from __future__ import annotations

import math

import numpy as np

from skillbus.manip.family.geometry import fold, top_down, turn, yaw_wxyz
from skillbus.manip.frames import angle_between
from skillbus.manip.registry import register_skill
from skillbus.manip.skill import ManipSkill

LINEAR = {"motion": "linear"}


def _vec3(value, what: str) -> np.ndarray:
    try:
        v = np.array([float(x) for x in value])
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be 3 numbers [x, y, z], not {value!r}") from None
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{what} must be 3 finite numbers [x, y, z], not {value!r}")
    return v


class _PathSkill(ManipSkill):
    """Checks that the tool passed within ``tolerance_m`` of each waypoint when its
    command finished."""
    defaults = {"tolerance_m": 0.005}
    options = ()

    def is_subtask_done(self):
        if not self.controller.head_finished:
            return False
        p, _ = self.controller.get_ee_pose()
        self.reached.append(float(np.linalg.norm(p - np.asarray(self.manip_list[0][0]))))
        return True

    def is_success(self):
        worst = max(self.reached, default=0.0)
        if worst > float(self.cfg["tolerance_m"]):
            self.failure_reason = f"a waypoint was missed by {worst * 1000:.1f} mm"
            return False
        return True


@register_skill
class Move(_PathSkill):
    """Moves the tool by ``offset`` [dx, dy, dz] (m, base frame) along a straight line."""
    defaults = {**_PathSkill.defaults, "offset": [0.0, 0.0, 0.05]}

    def simple_generate_manip_cmds(self):
        p, q = self.controller.get_ee_pose()
        self.reached: list[float] = []
        self.manip_list = [(p + _vec3(self.cfg["offset"], "offset"), q, "dummy_forward", LINEAR)]


@register_skill
class Track(_PathSkill):
    """Follows ``waypoints`` (offsets [dx, dy, dz] from where the tool starts, base frame)
    with straight segments."""
    defaults = {**_PathSkill.defaults}
    options = ("waypoints",)

    def simple_generate_manip_cmds(self):
        wps = self.cfg.get("waypoints")
        if not isinstance(wps, list) or not wps:
            raise ValueError("track needs waypoints, a list of [dx, dy, dz] offsets")
        p, q = self.controller.get_ee_pose()
        self.reached = []
        self.manip_list = [(p + _vec3(w, f"waypoints[{i}]"), q, "dummy_forward", LINEAR) for i, w in enumerate(wps)]


@register_skill
class ApproachRotate(ManipSkill):
    """Goes over an object (``height`` m above it) with the tool pointing down, then turns
    the wrist in place to the object's yaw (folded to the nearest square grasp)."""
    elements = {"Object": "skiros:Product"}
    defaults = {"height": 0.12, "tolerance_rad": 0.035}
    options = ()

    def simple_generate_manip_cmds(self):
        p, q = self.task.object_pose(self.cfg["Object"])
        _, tq = self.controller.get_ee_pose()
        above = p + np.array([0.0, 0.0, float(self.cfg["height"])])
        self.goal_yaw = fold(yaw_wxyz(q))
        self.manip_list = [(above, top_down(fold(yaw_wxyz(tq)) if abs(tq[2]) > 0.9 else 0.0), "dummy_forward",
                            {"motion": "free"}),
                           (above, top_down(self.goal_yaw), "dummy_forward", LINEAR)]

    def is_success(self):
        _, q = self.controller.get_ee_pose()
        err = angle_between(q, top_down(self.goal_yaw))
        if err > float(self.cfg["tolerance_rad"]):
            self.failure_reason = f"the wrist is {math.degrees(err):.1f} degrees from the object's yaw"
            return False
        return True


@register_skill
class Flip(ManipSkill):
    """Turns an object onto its side: picks it (welded to the tool, ``attach``), lifts it,
    tilts the tool by ``angle`` rad about the horizontal axis across the fingers, puts it
    down ``drop`` m above where it was and lets go. Succeeds when the object's z axis has
    turned at least ``min_tilt`` rad from the vertical."""
    elements = {"Object": "skiros:Product"}
    defaults = {"approach": 0.10, "lift": 0.15, "angle": 1.5708, "drop": 0.04, "min_tilt": 1.0, "attach": True}
    options = ()

    def simple_generate_manip_cmds(self):
        obj = self.cfg["Object"]
        self.label = self.task.label_of(obj)
        p, q = self.task.object_pose(obj)
        yaw = fold(yaw_wxyz(q))
        gq = top_down(yaw)
        gp = p + np.array([0.0, 0.0, 0.005])
        up = np.array([0.0, 0.0, 1.0])
        across = np.array([math.cos(yaw), math.sin(yaw), 0.0])  # the tool's x axis, horizontal
        tilted = turn(gq, across, float(self.cfg["angle"]))
        hold = gp + up * float(self.cfg["lift"])
        down = gp + up * float(self.cfg["drop"])
        cmds = [(gp + up * float(self.cfg["approach"]), gq, "open_gripper", {"motion": "free"}),
                (gp, gq, "close_gripper", LINEAR)]
        if self.cfg.get("attach"):
            cmds.append((gp, gq, "attach_obj", {"motion": "none", "object": self.label}))
        cmds += [(hold, gq, "dummy_forward", LINEAR), (hold, tilted, "dummy_forward", {"motion": "free"}),
                 (down, tilted, "dummy_forward", LINEAR)]
        if self.cfg.get("attach"):
            cmds.append((down, tilted, "detach_obj", {"motion": "none", "object": self.label}))
        cmds += [(down, tilted, "open_gripper", {"motion": "none"}), (hold, tilted, "dummy_forward", LINEAR)]
        self.manip_list = cmds

    def is_success(self):
        from skillbus.manip.frames import wxyz_to_xyzw
        from skillbus.quat import rotate
        _, q = self.task.object_pose(self.cfg["Object"])
        z = rotate(wxyz_to_xyzw(q), (0.0, 0.0, 1.0))
        tilt = math.acos(max(-1.0, min(1.0, z[2])))
        # A cube turned by a quarter lies on a side: its z axis horizontal, or turned on round
        self.tilt = tilt
        if tilt < float(self.cfg["min_tilt"]):
            self.failure_reason = f"{self.label} tilted only {math.degrees(tilt):.0f} degrees"
            return False
        return True


@register_skill
class Scan(_PathSkill):
    """Looks at an object from ``views`` viewpoints on a circle of ``radius`` m around it,
    ``height`` m above it, the tool pointing down and turned to face the object's centre."""
    elements = {"Object": "skiros:Product"}
    defaults = {**_PathSkill.defaults, "views": 4, "radius": 0.06, "height": 0.15}

    def simple_generate_manip_cmds(self):
        p, _ = self.task.object_pose(self.cfg["Object"])
        n = int(self.cfg["views"])
        if n < 1:
            raise ValueError("scan: views must be at least 1")
        r, h = float(self.cfg["radius"]), float(self.cfg["height"])
        self.reached = []
        cmds = []
        for k in range(n):
            a = 2 * math.pi * k / n
            vp = p + np.array([r * math.cos(a), r * math.sin(a), h])
            cmds.append((vp, top_down(fold(a)), "dummy_forward", {"motion": "free" if k == 0 else "linear"}))
        self.viewpoints = [c[0] for c in cmds]
        self.manip_list = cmds
