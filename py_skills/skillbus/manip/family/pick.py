"""Pick and place: pick (top-down, the yaw of the object folded to the nearest square
grasp), manualpick (a grasp pose given relative to the object), dynamicpick (the first
annotated grasp candidate the motion service can reach), failpick (a pick that misses on
purpose: a labelled failure for the dataset) and place.

A pick's command list: over the grasp with the gripper opened, straight down, close the
gripper (and, with ``attach: true``, weld the object to the tool), straight up. It
succeeds when the object has risen with the tool; the world model then says the
gripper contains it.
"""

from __future__ import annotations

import numpy as np

from skillbus.manip.family.geometry import compose, fold, pose7, top_down, yaw_wxyz
from skillbus.manip.family.world import contained_ops, shows_contained, view_to_world, world_of
from skillbus.manip.registry import register_skill
from skillbus.manip.skill import ManipSkill
from skillbus.skill import ConditionRelation

LINEAR = {"motion": "linear"}


class _PickBase(ManipSkill):
    elements = {"Object": "skiros:Product"}
    defaults = {"approach": 0.10, "grasp_height": 0.005, "lift": 0.10, "attach": False}
    options = ()

    @classmethod
    def describe(cls, d):
        d.addPreCondition(ConditionRelation("NotHolding", "skiros:contain", "Gripper", "Object", False))
        d.addPostCondition(ConditionRelation("Holding", "skiros:contain", "Gripper", "Object", True))

    def grasp_pose(self) -> tuple[np.ndarray, np.ndarray]:
        p, q = self.task.object_pose(self.cfg["Object"])
        return p + np.array([0.0, 0.0, float(self.cfg["grasp_height"])]), top_down(fold(yaw_wxyz(q)))

    def simple_generate_manip_cmds(self):
        obj = self.cfg["Object"]
        self.label = self.task.label_of(obj)
        self.start_z = float(self.task.object_pose(obj)[0][2])
        gp, gq = self.grasp_pose()
        up = np.array([0.0, 0.0, 1.0])
        cmds = [(gp + up * float(self.cfg["approach"]), gq, "open_gripper", {"motion": "free"}),
                (gp, gq, "close_gripper", LINEAR)]
        if self.cfg.get("attach"):
            cmds.append((gp, gq, "attach_obj", {"motion": "none", "object": self.label}))
        cmds.append((gp + up * float(self.cfg["lift"]), gq, "dummy_forward", LINEAR))
        self.manip_list = cmds

    def is_success(self):
        p, _ = self.task.object_pose(self.cfg["Object"])
        tool, _ = self.controller.get_ee_pose()
        risen = float(p[2]) - self.start_z
        near = float(np.linalg.norm(p[:2] - tool[:2]))
        if risen < 0.5 * float(self.cfg["lift"]) or near > 0.05:
            self.failure_reason = (f"{self.label} is not in the gripper: it rose {risen * 100:.1f} cm "
                                   f"and is {near * 100:.1f} cm from the tool")
            return False
        return True

    def world_ops(self):
        wmi, gripper = self.task.wmi, self.robot.gripper
        if wmi is None or not gripper:
            return []
        tool_p, tool_q = self.controller.get_ee_pose()
        return contained_ops(wmi, self.cfg["Object"], gripper, world_of(self.task, self.cfg["Object"]),
                             view_to_world(self.task, tool_p, tool_q))

    def world_shows(self):
        return shows_contained(self.task.wmi, self.robot.gripper, self.cfg["Object"])


@register_skill
class Pick(_PickBase):
    """Picks an object from above."""


@register_skill
class Manualpick(_PickBase):
    """Picks an object with a grasp pose given in its configuration: ``grasp_pose``
    [x, y, z, qw, qx, qy, qz], the tool centre point relative to the object's frame."""
    options = ("grasp_pose",)

    def grasp_pose(self):
        if "grasp_pose" not in self.cfg:
            raise ValueError("manualpick needs grasp_pose [x, y, z, qw, qx, qy, qz] (relative to the object)")
        local = pose7(self.cfg["grasp_pose"], "grasp_pose")
        return compose(self.task.object_pose(self.cfg["Object"]), list(local[0]) + list(local[1]))


DEFAULT_CANDIDATES = [  # relative to the object: top-down at four yaws, then tilted 20 degrees from each side
    [0, 0, 0.005, 0, 1, 0, 0], [0, 0, 0.005, 0, 0.7071068, 0.7071068, 0],
    [0, 0, 0.005, 0, 0, 1, 0], [0, 0, 0.005, 0, -0.7071068, 0.7071068, 0],
]


@register_skill
class Dynamicpick(_PickBase):
    """Picks an object with the first of its grasp candidates (``candidates``: poses
    relative to the object, [x, y, z, qw, qx, qy, qz]) whose pre-grasp the motion service
    can reach; the chosen index is in ``self.chosen`` and in the skill's message."""
    options = ("candidates",)

    def grasp_pose(self):
        frame = self.task.object_pose(self.cfg["Object"])
        tried = []
        for i, c in enumerate(self.cfg.get("candidates") or DEFAULT_CANDIDATES):
            local = pose7(c, f"candidates[{i}]")
            gp, gq = compose(frame, list(local[0]) + list(local[1]))
            pre = gp + np.array([0.0, 0.0, float(self.cfg["approach"])])
            err = self.controller.reachable(pre, gq)
            if not err:
                self.chosen = i
                return gp, gq
            tried.append(f"{i}: {err}")
        raise ValueError("dynamicpick: no grasp candidate is reachable (" + "; ".join(tried) + ")")


@register_skill
class Failpick(_PickBase):
    """A pick that misses on purpose (``miss_offset`` m beside the object): a labelled
    failure, so that a dataset holds failures that look like real ones."""
    defaults = {**_PickBase.defaults, "miss_offset": 0.07}

    def grasp_pose(self):
        gp, gq = super().grasp_pose()
        return gp + np.array([float(self.cfg["miss_offset"]), 0.0, 0.0]), gq

    def is_success(self):
        super().is_success()
        self.failure_reason = f"failpick: a labelled failure (the grasp aimed {self.cfg['miss_offset']} m beside " \
                              f"{self.label})"
        return False


@register_skill
class Place(ManipSkill):
    """Puts the held object down over a Location: over it (``offset`` [dx, dy] from its
    origin, base frame) at ``release_height`` above its origin, opens the gripper (and
    detaches a welded object), and goes up. Over an articulated part (a drawer) the
    place is ``inside`` m behind its handle, along the joint's axis, and
    ``release_height`` above the handle."""
    elements = {"Object": "skiros:Product", "Location": "skiros:Location"}
    defaults = {"above": 0.10, "release_height": 0.30, "inside": 0.13, "offset": [0.0, 0.0], "attach": False}
    options = ()

    @classmethod
    def describe(cls, d):
        d.addPreCondition(ConditionRelation("Holding", "skiros:contain", "Gripper", "Object", True))
        d.addPostCondition(ConditionRelation("Contains", "skiros:contain", "Location", "Object", True))

    def target(self) -> np.ndarray:
        loc = self.cfg["Location"]
        dx, dy = (float(v) for v in self.cfg.get("offset", [0.0, 0.0]))
        try:
            j = self.task.joint(loc) if self.task.articulation is not None else None
        except Exception:
            j = None
        if j is not None and j.handle is not None:
            p = j.handle[0] - j.axis * float(self.cfg["inside"])
        else:
            p, _ = self.task.object_pose(loc)
        return np.array([p[0] + dx, p[1] + dy, p[2] + float(self.cfg["release_height"])])

    def simple_generate_manip_cmds(self):
        self.label = self.task.label_of(self.cfg["Object"])
        _, tq = self.controller.get_ee_pose()
        t = self.target()
        up = np.array([0.0, 0.0, float(self.cfg["above"])])
        self.release = t
        cmds = [(t + up, tq, "dummy_forward", {"motion": "free"}), (t, tq, "dummy_forward", LINEAR)]
        if self.cfg.get("attach"):
            cmds.append((t, tq, "detach_obj", {"motion": "none", "object": self.label}))
        cmds += [(t, tq, "open_gripper", {"motion": "none"}), (t + up, tq, "dummy_forward", LINEAR)]
        self.manip_list = cmds

    def is_success(self):
        p, _ = self.task.object_pose(self.cfg["Object"])
        off = float(np.linalg.norm(p[:2] - self.release[:2]))
        below = float(self.release[2] - p[2])
        if off > 0.06 or below < 0.0:
            self.failure_reason = f"{self.label} is {off * 100:.1f} cm beside the place, {below * 100:.1f} cm below it"
            return False
        return True

    def world_ops(self):
        if self.task.wmi is None:
            return []
        loc = self.cfg["Location"]
        return contained_ops(self.task.wmi, self.cfg["Object"], loc, world_of(self.task, self.cfg["Object"]))

    def world_shows(self):
        return shows_contained(self.task.wmi, self.cfg["Location"], self.cfg["Object"])
