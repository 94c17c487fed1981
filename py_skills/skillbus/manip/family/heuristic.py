"""Heuristic skills: goto_pose, gripper_action, joint_ctrl and wait: one command each
(or a few), checked by where the robot ends."""

from __future__ import annotations

import numpy as np

from skillbus.manip.family.geometry import pose7
from skillbus.manip.frames import angle_between
from skillbus.manip.registry import register_skill
from skillbus.manip.skill import ManipSkill


@register_skill
class GotoPose(ManipSkill):
    """Moves the tool to ``pose`` [x, y, z, qw, qx, qy, qz] in the base frame (``motion``:
    free or linear)."""
    defaults = {"motion": "free", "tolerance_m": 0.005, "tolerance_rad": 0.02}
    options = ("pose",)

    def simple_generate_manip_cmds(self):
        if "pose" not in self.cfg:
            raise ValueError("goto_pose needs pose [x, y, z, qw, qx, qy, qz] (base frame)")
        self.goal = pose7(self.cfg["pose"], "pose")
        self.manip_list = [(self.goal[0], self.goal[1], "dummy_forward", {"motion": self.cfg["motion"]})]

    def is_success(self):
        p, q = self.controller.get_ee_pose()
        dp, dq = float(np.linalg.norm(p - self.goal[0])), angle_between(q, self.goal[1])
        if dp > float(self.cfg["tolerance_m"]) or dq > float(self.cfg["tolerance_rad"]):
            self.failure_reason = f"the tool is {dp * 1000:.1f} mm and {dq:.3f} rad from the pose"
            return False
        return True


@register_skill
class GripperAction(ManipSkill):
    """Opens (``gripper_state: 1``) or closes (``-1``) the gripper where the tool is."""
    defaults = {"gripper_state": 1}
    options = ()

    def simple_generate_manip_cmds(self):
        state = int(self.cfg["gripper_state"])
        if state not in (1, -1):
            raise ValueError(f"gripper_action: gripper_state must be 1 (open) or -1 (close), not {state}")
        p, q = self.controller.get_ee_pose()
        self.manip_list = [(p, q, "open_gripper" if state == 1 else "close_gripper", {"motion": "none"})]


@register_skill
class JointCtrl(ManipSkill):
    """Moves the arm's joints to ``joints`` ({name: position}, rad); joints not named stay."""
    defaults = {"tolerance_rad": 0.01}
    options = ("joints",)

    def simple_generate_manip_cmds(self):
        joints = self.cfg.get("joints")
        if not isinstance(joints, dict) or not joints:
            raise ValueError("joint_ctrl needs joints, a mapping {joint: position}")
        self.goal = {str(k): float(v) for k, v in joints.items()}
        p, q = self.controller.get_ee_pose()
        self.manip_list = [(p, q, "dummy_forward", {"motion": "joints", "joints": self.goal})]

    def is_success(self):
        now = self.controller.joint_positions()
        off = {k: abs(now[k] - v) for k, v in self.goal.items()}
        worst = max(off, key=off.get)
        if off[worst] > float(self.cfg["tolerance_rad"]):
            self.failure_reason = f"{worst} is {off[worst]:.3f} rad from its target"
            return False
        return True


@register_skill
class Wait(ManipSkill):
    """Waits ``frames`` ticks where the robot is."""
    defaults = {"frames": 10}
    options = ()

    def simple_generate_manip_cmds(self):
        p, q = self.controller.get_ee_pose()
        self.manip_list = [(p, q, "wait", {"motion": "none", "frames": int(self.cfg["frames"])})]
