"""A stand-in for a real robot's drivers, with no physics server: what a real arm's driver
and a camera's driver must do on the robot's channels, on the wall clock, and nothing
more.

* every 20 ms: robot_arm_state_t on SB_ROBOT_ARM_STATE (the arm's six joints, the tool
  pose, the command being played) and robot_objects_t on SB_ROBOT_OBJECTS (the objects
  of --objects, a JSON list of [name, x, y, z]);
* robot_arm_cmd_t from SB_ROBOT_ARM_CMD: checked (known joints, finite positions that
  match them, increasing times, joint1 within +-JOINT1_LIMIT rad), answered on
  SB_ROBOT_CMD_REPLY (robot_cmd_reply_t), and played kinematically: the joints follow
  the points linearly in time from where they were (a point at 0 s is reached at once),
  with no tracking error. The tool pose stays fixed: this stand-in has no kinematics
  (the skills it serves here, Locate and MoveArm, do not read it).

It also listens to every SB_SIM_ channel, to show that nobody talks to a simulator.
Each accepted or rejected command is a JSON line on stdout as it comes; SIGTERM ends it
with a JSON summary line.
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
import time

from skillbus.bus import BusError, channel, open_bus
from skillbus.msgs import decode, robot_arm_cmd_t, robot_arm_state_t, robot_cmd_reply_t, robot_object_t, robot_objects_t
from skillbus.robot.messages import arm_cmd_channel, arm_state_channel, objects_channel, reply_channel

JOINTS = [f"joint{i}" for i in range(1, 7)]
HOME = [0.0, 0.2, 1.6, 0.0, 1.3416, 0.0]
TOOL = [0.3, 0.0, 0.6, 0.0, 1.0, 0.0, 0.0]
PERIOD_S = 0.02


class Driver:
    def __init__(self, bus, objects: list, joint1_limit: float) -> None:
        self.bus, self.objects, self.joint1_limit = bus, objects, joint1_limit
        self.q = list(HOME)
        self.cmd_id = ""
        self.start_q: list[float] = []
        self.points: list[tuple[float, list[float]]] = []  # (s from the start, all six joints)
        self.started = 0.0
        self.seq = 0
        self.frame = 0
        self.sim_messages: dict[str, int] = {}
        self.commands: list[dict] = []
        bus.subscribe(arm_cmd_channel(), lambda ch, d: self.on_command(d))
        count = (lambda ch, d: self.sim_messages.__setitem__(ch, self.sim_messages.get(ch, 0) + 1))
        if bus.url.startswith("dds://"):  # (no patterns on DDS: each of the simulator's channels)
            for name in ("SB_SIM_STATE", "SB_SIM_GRIPPER_CMD", "SB_SIM_CMD_REPLY", "SB_SIM_REQ", "SB_SIM_REP"):
                bus.subscribe(channel(name), count)
        else:  # every channel of the simulator's, by LCM's regular expression
            bus.subscribe(channel("SB_SIM_") + ".*", count)

    def check(self, m: robot_arm_cmd_t) -> str:
        if not m.joint_names or not m.points:
            return "the command names no joints or has no points"
        for n in m.joint_names:
            if n not in JOINTS:
                return f"unknown arm joint {n!r}"
        last = -1
        for i, p in enumerate(m.points):
            if len(p.positions) != len(m.joint_names) or not all(math.isfinite(x) for x in p.positions):
                return f"point {i}: positions do not match the joints or are not finite"
            if p.time_from_start_ns <= last:
                return f"point {i}: times do not increase"
            last = p.time_from_start_ns
            if "joint1" in m.joint_names and abs(p.positions[m.joint_names.index("joint1")]) > self.joint1_limit:
                return f"joint1 target {p.positions[m.joint_names.index('joint1')]:.3f} at point {i} is outside " \
                       f"+-{self.joint1_limit} rad"
        return ""

    def on_command(self, data: bytes) -> None:
        m = decode(robot_arm_cmd_t, data)
        if m is None:
            return
        error = self.check(m)
        if not error:
            self.start_q, self.started, self.cmd_id = list(self.q), time.monotonic(), m.id
            self.points = []
            for p in m.points:
                target = list(self.points[-1][1] if self.points else self.q)
                for n, x in zip(m.joint_names, p.positions):
                    target[JOINTS.index(n)] = x
                self.points.append((p.time_from_start_ns * 1e-9, target))
        r = robot_cmd_reply_t()
        r.header.frame, r.header.sender = self.frame, "driver"
        r.id, r.command, r.accepted, r.error = m.id, "arm", not error, error
        self.bus.publish(reply_channel(), r.encode())
        record = {"id": m.id, "joints": list(m.joint_names), "points": len(m.points), "accepted": not error,
                  "error": error, "last": list(m.points[-1].positions) if m.points else []}
        self.commands.append(record)
        print(json.dumps({"command": record}), flush=True)

    def follow(self, now: float) -> bool:
        """Moves the joints along the command; True while it is still playing."""
        if not self.points:
            return False
        t = now - self.started
        before_t, before_q = 0.0, self.start_q
        for pt, pq in self.points:
            if t < pt:
                a = (t - before_t) / (pt - before_t)
                self.q = [x + a * (y - x) for x, y in zip(before_q, pq)]
                return True
            before_t, before_q = pt, pq
        self.q = list(self.points[-1][1])
        return False

    def publish(self, now: float) -> None:
        moving = self.follow(now)
        s = robot_arm_state_t()
        s.joint_names, s.num_joints = list(JOINTS), len(JOINTS)
        s.position, s.velocity, s.effort = list(self.q), [0.0] * 6, [0.0] * 6
        s.tool_pose = list(TOOL)
        s.arm_command_id, s.arm_moving, s.arm_tracking_error = self.cmd_id, moving, 0.0
        o = robot_objects_t()
        for name, x, y, z in self.objects:
            d = robot_object_t()
            d.name, d.pose = name, [x, y, z, 0.0, 0.0, 0.0, 1.0]
            o.objects.append(d)
        o.num_objects = len(o.objects)
        for ch, msg in ((arm_state_channel(), s), (objects_channel(), o)):
            msg.header.frame, msg.header.sim_time_ns, msg.header.sender, msg.header.seq = \
                self.frame, self.frame * int(PERIOD_S * 1e9), "driver", self.seq
            self.seq += 1
            self.bus.publish(ch, msg.encode())
        self.frame += 1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--objects", default="[]", help='JSON list of [name, x, y, z] (world frame)')
    ap.add_argument("--joint1-limit", type=float, default=math.pi)
    args = ap.parse_args()
    stop = {"now": False}
    signal.signal(signal.SIGTERM, lambda *_: stop.__setitem__("now", True))
    bus = open_bus()
    d = Driver(bus, json.loads(args.objects), args.joint1_limit)
    print(json.dumps({"driver": "ready"}), flush=True)
    next_t = time.monotonic()
    while not stop["now"]:
        now = time.monotonic()
        if now >= next_t:
            d.publish(now)
            next_t += PERIOD_S
            if now - next_t > 1.0:
                next_t = now
        try:
            bus.handle(max(0.0, min(next_t - time.monotonic(), 0.2)))
        except (BusError, OSError):  # the wait ended by SIGTERM (EINTR)
            signal.pthread_sigmask(signal.SIG_BLOCK, [])  # the Python handler runs by now at the latest
            if not stop["now"]:
                raise
    print(json.dumps({"commands": d.commands, "sim_messages": d.sim_messages, "frames": d.frame,
                      "sim_modules": sorted(m for m in sys.modules if m.startswith("skillbus.sim"))}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
