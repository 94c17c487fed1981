"""Articulation skills: open and close (a drawer's prismatic joint, a door's revolute
one) and rotate (a revolute joint by a given angle). The Object is the world model's
element of the joint (``skiros:Drawer-12``, label ``cabinet/drawer_joint``).

The command list: over the handle's annotated grasp with the gripper opened, down onto
it, close the gripper, then the handle's path as the joint moves (straight along a
prismatic axis in steps of ``step_m``; an arc about a revolute axis in steps of
``step_rad``, the tool turning with the handle), open the gripper, and up. It succeeds
when the joint has moved at least ``success_fraction`` of the way; the world model then
has the joint's new position (``skiros:JointPosition``).
"""

from __future__ import annotations

import math

import numpy as np

from skillbus.manip.family.geometry import rotate_about
from skillbus.manip.family.world import joint_position_op, shows_joint
from skillbus.manip.registry import register_skill
from skillbus.manip.skill import ManipSkill

LINEAR = {"motion": "linear"}
# The handle's path drags the mechanism: the arm may end a step held back by its damping
# and friction, a little short of the trajectory's end.
DRAG = {"motion": "linear", "settle_rad": 0.05, "fallback": "free"}


class _Articulate(ManipSkill):
    elements = {"Object": "skiros:ArticulatedPart"}
    defaults = {"approach": 0.08, "step_m": 0.03, "step_rad": 0.15, "success_fraction": 0.8, "speed": 0.3}
    options = ()

    def delta(self, j) -> float:
        raise NotImplementedError

    def simple_generate_manip_cmds(self):
        j = self.task.joint(self.cfg["Object"])
        if j.handle is None:
            raise ValueError(f"{j.label} has no handle annotation in the scene")
        self.joint_label, self.start = j.label, j.position
        d = self.delta(j)
        goal = min(max(j.position + d, j.lower), j.upper)
        self.want = goal - j.position
        hp, hq = j.handle
        up = np.array([0.0, 0.0, float(self.cfg["approach"])])
        cmds = [(hp + up, hq, "open_gripper", {"motion": "free"}), (hp, hq, "close_gripper", LINEAR)]
        if j.kind == "prismatic":
            n = max(1, math.ceil(abs(self.want) / float(self.cfg["step_m"])))
            for k in range(1, n + 1):
                cmds.append((hp + j.axis * self.want * k / n, hq, "dummy_forward", DRAG))
            end_p, end_q = hp + j.axis * self.want, hq
        else:
            n = max(1, math.ceil(abs(self.want) / float(self.cfg["step_rad"])))
            for k in range(1, n + 1):
                p, q = rotate_about(hp, j.axis, j.origin, self.want * k / n, hq)
                cmds.append((p, q, "dummy_forward", DRAG))
            end_p, end_q = rotate_about(hp, j.axis, j.origin, self.want, hq)
        cmds += [(end_p, end_q, "open_gripper", {"motion": "none"}), (end_p + up, end_q, "dummy_forward", LINEAR)]
        self.manip_list = cmds

    def is_success(self):
        j = self.task.joint(self.cfg["Object"])
        self.end = j.position
        moved = j.position - self.start
        unit = "m" if j.kind == "prismatic" else "rad"
        if abs(self.want) < 1e-6:
            return True  # already there
        if moved / self.want < float(self.cfg["success_fraction"]):
            self.failure_reason = (f"{self.joint_label} moved {moved:+.3f} {unit} of the {self.want:+.3f} {unit} "
                                   f"wanted (now {j.position:.3f} {unit})")
            return False
        return True

    def world_ops(self):
        wmi = self.task.wmi
        if wmi is None:
            return []
        e = self.task._element(self.cfg["Object"])
        return [] if e is None else [joint_position_op(wmi, e.id, self.end)]

    def world_shows(self):
        e = self.task._element(self.cfg["Object"])
        return e is None or shows_joint(self.task.wmi, e.id, self.end)


@register_skill
class Open(_Articulate):
    """Opens a drawer by ``distance`` m or a door by ``angle`` rad (within the joint's
    limits)."""
    defaults = {**_Articulate.defaults, "distance": 0.15, "angle": 1.2}

    def delta(self, j):
        return float(self.cfg["distance"] if j.kind == "prismatic" else self.cfg["angle"])


@register_skill
class Close(_Articulate):
    """Closes a drawer or a door: back to the joint's lower limit."""

    def delta(self, j):
        return j.lower - j.position


@register_skill
class Rotate(_Articulate):
    """Turns a revolute joint by ``angle`` rad (signed), within its limits."""
    defaults = {**_Articulate.defaults, "angle": 0.5}

    def delta(self, j):
        if j.kind != "revolute":
            raise ValueError(f"rotate: {j.label} is {j.kind}, not revolute")
        return float(self.cfg["angle"])
