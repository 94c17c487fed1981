"""What a manipulation skill sees of the robot and the task (InternDataEngine hands its
skills a robot, a controller and a task object; these are skillbus's):

- ``Controller``: the end effector's pose in the arm's base frame (numpy, q as w x y z),
  the arm's joints, and the executor's counters (planning failures, ticks on the head
  command, whether the head command has finished);
- ``TaskView``: where objects are (the robot's camera: its detections by name; else the
  world model), the articulated objects' joints and their annotated handle grasps (the
  articulation interface), and the world model's elements by label.

Both answer in the base frame, as InternDataEngine's skills expect. The base frame is the
robot's element pose in the world model (the scene's robot pose).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from skillbus.manip.frames import Pose, to_base, to_world


class ViewError(RuntimeError):
    pass


@dataclass
class RobotInfo:
    arm: str          # the world model's Arm element
    gripper: str      # its Gripper element ("" if none)
    robot: str        # the Robot element that has the arm ("" if the world model does not say)


class Controller:
    def __init__(self, arm: Any, base: Pose) -> None:
        self.arm = arm
        self.base = base
        self.num_plan_failed = 0
        self.num_last_cmd = 0       # ticks spent on the head command
        self.head_finished = False  # the head command's motion and action are done
        self.last_plan_error = ""

    def get_ee_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """The tool centre point in the base frame: (p, q as w x y z)."""
        s = self.arm.state
        if s is None:
            raise ViewError("no arm state yet (is the physics server or the arm's driver running?)")
        t = s.tool_pose
        p, q = to_base(self.base, t[:3], t[3:7])
        return np.array(p), np.array(q)

    def reachable(self, p: Any, q_wxyz: Any) -> str:
        """"" when the motion service plans a joint-space move from here to the pose (base
        frame), else its reason."""
        wp, wq = self.to_world(p, q_wxyz)
        try:
            plan = self.arm.plan(list(wp) + list(wq), cartesian=False)
        except Exception as e:
            return str(e)
        return "" if plan.ok else (plan.error or "no plan")

    def joint_positions(self) -> dict[str, float]:
        return dict(zip(self.arm.joint_names(), self.arm.joints()))

    def to_world(self, p: Any, q_wxyz: Any) -> Pose:
        return to_world(self.base, p, q_wxyz)


@dataclass
class Joint:
    """An articulated object's joint as the articulation interface reports it, in the
    base frame."""
    object: str
    joint: str
    concept: str
    kind: str               # prismatic | revolute
    position: float
    lower: float
    upper: float
    axis: np.ndarray        # unit, base frame
    origin: np.ndarray      # a point on the axis, base frame
    handle: tuple[np.ndarray, np.ndarray] | None  # grasp pose (p, q w x y z), base frame

    @property
    def label(self) -> str:
        return f"{self.object}/{self.joint}"


class TaskView:
    def __init__(self, base: Pose, wmi: Any = None, camera: Any = None, articulation: Any = None) -> None:
        self.base, self.wmi, self.camera, self.articulation = base, wmi, camera, articulation

    def _element(self, name: str) -> Any:
        if self.wmi is None:
            return None
        try:
            return self.wmi.get_element(name)
        except Exception:
            pass
        for e in self.wmi.get_elements():
            if e.label == name:
                return e
        return None

    def label_of(self, name: str) -> str:
        e = self._element(name)
        return e.label if e is not None and e.label else name

    def object_pose(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """An object's pose (p, q as w x y z) in the base frame, by world-model id or label:
        the camera's detection of it when there is one, else the world model's pose."""
        label = self.label_of(name)
        if self.camera is not None:
            for o in self.camera.objects():
                if o.name == label:
                    p, q = to_base(self.base, o.pose[:3], o.pose[3:7])
                    return np.array(p), np.array(q)
        e = self._element(name)
        if e is None:
            raise ViewError(f"no object {name!r}: not seen by the camera and not in the world model")
        from skillbus.world.poses import world_pose
        wp, wq = world_pose(self.wmi, e.id)
        p, q = to_base(self.base, wp, wq)
        return np.array(p), np.array(q)

    def object_size(self, name: str, default: float = 0.05) -> float:
        e = self._element(name)
        if e is not None and e.hasProperty("skiros:Size", not_none=True):
            return float(e.getProperty("skiros:Size").value)
        return default

    def joints(self) -> list[Joint]:
        if self.articulation is None:
            raise ViewError("this skill process has no articulation interface "
                            "(--interface articulation=skillbus.robot.articulation)")
        out = []
        for j in self.articulation.joints():
            bq = self.base[1]
            from skillbus.quat import qconj, rotate
            axis = np.array(rotate(qconj(bq), j.axis))
            origin, _ = to_base(self.base, j.origin, (0.0, 0.0, 0.0, 1.0))
            handle = None
            if j.has_handle:
                hp, hq = to_base(self.base, j.handle_pose[:3], j.handle_pose[3:7])
                handle = (np.array(hp), np.array(hq))
            out.append(Joint(j.object, j.joint, j.concept, j.kind, float(j.position), float(j.lower),
                             float(j.upper), axis, np.array(origin), handle))
        return out

    def joint(self, name: str) -> Joint:
        """A joint by "object/joint", by world-model id or label of its element ("skiros:Drawer-12"
        has the label "cabinet/drawer_joint"), or by joint name alone when that is unique."""
        label = self.label_of(name)
        joints = self.joints()
        found = [j for j in joints if j.label == label] or [j for j in joints if j.joint == label]
        if len(found) != 1:
            have = ", ".join(j.label for j in joints) or "none"
            raise ViewError(f"no articulated joint {name!r} (the articulation interface reports: {have})")
        return found[0]
