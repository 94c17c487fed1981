"""The skill side talks to the robot only through the robot's channels: importing the
manipulation skills and the robot interfaces (arm, camera) in a fresh interpreter loads
nothing of skillbus.sim, none of the skillbus modules it loads names an SB_SIM_ channel,
and the arm and camera interfaces, on the wall clock and under lockstep, subscribe and
publish only on SB_ROBOT_* channels (and the motion service's RPC), never on the
simulator's."""

from __future__ import annotations

import json
import subprocess
import sys

PROBE = r'''
import json, sys
from pathlib import Path

import skillbus.skills.gripper  # noqa: F401
import skillbus.skills.manipulation  # noqa: F401
from skillbus.msgs import motion_plan_t, robot_arm_state_t, robot_object_t, robot_objects_t
from skillbus.robot import arm, camera
from skillbus.robot.messages import traj_point

out = {"sim_modules": sorted(m for m in sys.modules if m == "skillbus.sim" or m.startswith("skillbus.sim.")
                            or m.startswith("skillbus.can.device"))}  # the simulated gripper device too
out["naming_sb_sim"] = sorted(
    name for name, m in sys.modules.items()
    if (name == "skillbus" or name.startswith("skillbus.")) and getattr(m, "__file__", None) and "SB_SIM_" in Path(m.__file__).read_text()
    and name != "skillbus.channels")  # (the bus's naming rule lists which channels are a robot's own; it uses none)


class Bus:  # records what the interfaces do with the bus (wall clock)
    def __init__(self):
        self.subscribed, self.published, self.handlers = [], [], {}

    def subscribe(self, ch, handler, latest_only=False):
        self.subscribed.append(ch)
        self.handlers[ch] = handler
        return len(self.subscribed)

    def unsubscribe(self, sid):
        pass

    def publish(self, ch, data):
        self.published.append(ch)


class Stamped:
    def __init__(self, data):
        self.data = data


class Participant:  # records what they do under lockstep
    def __init__(self, bus):
        self.bus, self.subscribed, self.published, self.handlers = bus, [], [], {}

    def subscribe(self, ch, handler, latest_only=False):
        self.subscribed.append(ch)
        self.handlers[ch] = handler

    def publish(self, ch, msg):
        self.published.append(ch)


def arm_state():
    s = robot_arm_state_t()
    s.joint_names = [f"joint{i}" for i in range(1, 7)]
    s.num_joints = 6
    s.position, s.velocity, s.effort = [0.1] * 6, [0.0] * 6, [0.0] * 6
    s.tool_pose = [0.3, 0.0, 0.6, 0.0, 1.0, 0.0, 0.0]
    return s.encode()


def seen():
    m = robot_objects_t()
    o = robot_object_t()
    o.name, o.pose = "red", [0.4, 0.15, 0.425, 0.0, 0.0, 0.0, 1.0]
    m.objects, m.num_objects = [o], 1
    return m.encode()


plan = motion_plan_t()
plan.joint_names, plan.num_joints = [f"joint{i}" for i in range(1, 7)], 6
plan.points, plan.num_points = [traj_point(1.0, [0.2] * 6)], 1
for mode in ("wall_clock", "lockstep"):
    bus = Bus()
    p = Participant(bus) if mode == "lockstep" else None
    a, c = arm.interface(bus, p, ""), camera.interface(bus, p, "")
    feed = (lambda ch, d: p.handlers[ch](Stamped(d))) if p else (lambda ch, d: bus.handlers[ch](ch, d))
    feed("SB_ROBOT_ARM_STATE", arm_state())
    feed("SB_ROBOT_OBJECTS", seen())
    held = a.hold("stop-1")
    a.execute(plan, "move-1")
    out[mode] = {"subscribed": sorted(set(bus.subscribed + (p.subscribed if p else []))),
                 "published": sorted(set(bus.published + (p.published if p else []))),
                 "joints": a.joint_names(), "held": held, "tool": list(a.state.tool_pose),
                 "objects": [(o.name, list(o.pose)) for o in c.objects()]}
print(json.dumps(out))
'''


def test_the_skill_side_never_touches_the_simulator():
    r = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert out["sim_modules"] == [], "the skill side imported the simulator's package"
    assert out["naming_sb_sim"] == [], "a module of the skill side names a simulator channel"
    for mode in ("wall_clock", "lockstep"):
        got = out[mode]
        channels = got["subscribed"] + got["published"]
        assert not [ch for ch in channels if ch.startswith("SB_SIM_")], (mode, got)
        assert set(got["subscribed"]) == {"SB_ROBOT_ARM_STATE", "SB_ROBOT_CMD_REPLY", "SB_ROBOT_OBJECTS",
                                          "SB_MOTION_REP"}, (mode, got)
        assert got["published"] == ["SB_ROBOT_ARM_CMD"], (mode, got)
        # What the robot reported is what the skills see: the arm's joints as its driver
        # names them (no filtering), the tool pose, the camera's objects.
        assert got["joints"] == [f"joint{i}" for i in range(1, 7)] and got["held"] == [0.1] * 6
        assert got["tool"] == [0.3, 0.0, 0.6, 0.0, 1.0, 0.0, 0.0]
        assert got["objects"] == [["red", [0.4, 0.15, 0.425, 0.0, 0.0, 0.0, 1.0]]]


def test_every_message_type_has_a_fingerprint_of_its_own():
    """LCM's fingerprint hashes the fields, not the type's name: two types with the same
    fields (robot_cmd_reply_t and a sim_cmd_reply_t that still had its `command`) could
    not be told apart by lcm-spy or by decode()."""
    import importlib
    import pkgutil

    import skillbus_msgs
    by_print: dict[bytes, list[str]] = {}
    for m in pkgutil.iter_modules(skillbus_msgs.__path__):
        cls = getattr(importlib.import_module(f"skillbus_msgs.{m.name}"), m.name)
        by_print.setdefault(cls._get_packed_fingerprint(), []).append(m.name)
    assert [names for names in by_print.values() if len(names) > 1] == []
