"""``skillbus sim-script``: a lockstep participant that plays a command script against
the physics server and records what it publishes.

The script (JSON) lists commands at sim times::

    {"steps": [
       {"at_s": 0.0, "arm": {"id": "up", "joints": ["joint2"], "points": [[1.0, [0.3]]]}},
       {"at_s": 1.5, "gripper": {"id": "close", "width": 0.0, "speed": 0.05, "force_limit": 20}}
     ],
     "record_every": 10}

An ``arm`` step is the robot's arm command (robot_arm_cmd_t on SB_ROBOT_ARM_CMD, as the
skills send it), a ``gripper`` step the simulated fingers' (sim_gripper_cmd_t on
SB_SIM_GRIPPER_CMD). A step is sent in the first frame whose sim time is at least
``at_s``, so the same script gives the same messages in the same frames on every run.
Every ``record_every``-th ground-truth state (sim_state_t) and every command reply (both
channels) go to ``--out`` as JSON. Timing comes only from the frames: no wall clock, no
randomness.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

from skillbus.bus import open_bus
from skillbus.lockstep import LockstepParticipant, StampedMessage
from skillbus.msgs import decode, robot_cmd_reply_t, sim_cmd_reply_t, sim_state_t, test_sample_t
from skillbus.robot import messages as robot
from skillbus.sim.messages import (check_state, gripper_channel, gripper_command, reply_channel, state_channel,
                                   state_dict)
from skillbus.validate import BadValue, Rejects


class ScriptError(ValueError):
    pass


def load_script(path: str) -> dict[str, Any]:
    try:
        script = json.loads(Path(path).read_text())
    except (OSError, json.JSONDecodeError) as e:
        raise ScriptError(f"{path}: {e}") from e
    # Each step whole before the session: what was checked as it was played (a gripper
    # step without a width) failed its frame and so the whole lockstep session.
    if not isinstance(script, dict):
        raise ScriptError(f"{path}: a script is an object with steps, not a {type(script).__name__}")
    every = script.get("record_every", 10)
    if isinstance(every, bool) or not isinstance(every, int) or every < 1:
        raise ScriptError(f"{path}: record_every must be a whole number of frames, 1 or more, not {every!r}")
    steps = script.get("steps", [])
    if not isinstance(steps, list):
        raise ScriptError(f"{path}: steps must be a list")
    for i, s in enumerate(steps):
        if not isinstance(s, dict) or not _number(s.get("at_s")):
            raise ScriptError(f"{path}: steps[{i}] needs a number at_s")
        if not ({"arm", "gripper", "raw", "wrong_type"} & set(s)):
            raise ScriptError(f"{path}: steps[{i}] has no arm, gripper or raw command")
        why = _step_error(s)
        if why:
            raise ScriptError(f"{path}: steps[{i}]: {why}")
    script["steps"] = sorted(steps, key=lambda s: s["at_s"])  # stable: equal times keep file order
    return script


def _is_number(v: Any) -> bool:
    """A number (NaN too: a script may send one to see it refused)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _number(v: Any) -> bool:
    """A finite number (a step's time: it orders the steps)."""
    return _is_number(v) and math.isfinite(v)


def _step_error(s: dict[str, Any]) -> str:
    """What a step lacks to be played, or "" (the values themselves are the receivers' to
    judge: a script may send wrong ones on purpose)."""
    if "arm" in s:
        a = s["arm"]
        if not isinstance(a, dict) or not isinstance(a.get("joints"), list) or not isinstance(a.get("points"), list):
            return "arm needs joints and points"
        for j, pt in enumerate(a["points"]):
            if not isinstance(pt, list) or len(pt) not in (2, 3) or not _is_number(pt[0]) or not isinstance(pt[1], list):
                return f"arm.points[{j}] is not [t, q] or [t, q, qd]"
    if "gripper" in s:
        g = s["gripper"]
        if not isinstance(g, dict) or not _is_number(g.get("width")):
            return "gripper needs a number width"
        for k in ("speed", "force_limit"):
            if k in g and not _is_number(g[k]):
                return f"gripper.{k} is not a number"
    if "raw" in s:
        r = s["raw"]
        try:
            bytes.fromhex(r["hex"])
        except (TypeError, KeyError, ValueError):
            return "raw needs hex bytes"
    if "wrong_type" in s and s["wrong_type"] not in ("arm", "gripper"):
        return "wrong_type is arm or gripper"
    return ""


class ScriptPlayer:
    def __init__(self, p: LockstepParticipant, script: dict[str, Any]) -> None:
        self.p = p
        self.steps = list(script["steps"])
        self.record_every = int(script.get("record_every", 10))
        self.states: list[dict[str, Any]] = []
        self.replies: list[dict[str, Any]] = []
        self.last_msg: sim_state_t | None = None
        self.bad = 0  # messages not recorded: not decodable, or values not sane (by kind: rejects)
        self.rejects = Rejects("sim-script")
        p.subscribe(state_channel(), self.on_state)
        p.subscribe(reply_channel(), lambda m: self.on_reply(m, sim_cmd_reply_t))
        p.subscribe(robot.reply_channel(), lambda m: self.on_reply(m, robot_cmd_reply_t))
        p.on_frame = self.on_frame

    def on_state(self, m: StampedMessage) -> None:
        s = decode(sim_state_t, m.data)
        if s is None:
            self.bad += 1
            return
        try:
            check_state(s)
        except BadValue as e:
            self.bad += 1
            self.rejects.record(m.channel, e)
            return
        self.last_msg = s  # turned into plain data only when recorded (it costs more than the decode)
        if s.header.frame % self.record_every == 0:
            self.states.append(state_dict(s))

    def on_reply(self, m: StampedMessage, msg_type: type) -> None:
        r = decode(msg_type, m.data)
        if r is None:
            self.bad += 1
            return
        command = r.command if msg_type is robot_cmd_reply_t else "gripper"  # the simulator's replies: fingers
        self.replies.append({"frame": r.header.frame, "id": r.id, "command": command,
                             "accepted": bool(r.accepted), "error": r.error})

    def on_frame(self, frame: int, sim_time_ns: int) -> None:
        while self.steps and self.steps[0]["at_s"] * 1e9 <= sim_time_ns + 1:
            step = self.steps.pop(0)
            if "arm" in step:
                a = step["arm"]
                points = [robot.traj_point(*p) for p in a["points"]]  # [t, q] or [t, q, qd]
                self.p.publish(robot.arm_cmd_channel(), robot.arm_command(a.get("id", ""), a["joints"], points))
            if "gripper" in step:
                g = step["gripper"]
                self.p.publish(gripper_channel(), gripper_command(g.get("id", ""), g["width"], g.get("speed", 0.1),
                                                                  g.get("force_limit", 20.0)))
            if "wrong_type" in step:  # tests: a stamped message of another type on a command channel
                junk = test_sample_t()
                junk.text = "not a command"
                self.p.publish(robot.arm_cmd_channel() if step["wrong_type"] == "arm" else gripper_channel(), junk)
            if "raw" in step:  # tests: bytes that are not a valid command, on a command channel
                r = step["raw"]
                self.p.bus.publish(robot.arm_cmd_channel() if r.get("channel") == "arm" else gripper_channel(),
                                   bytes.fromhex(r["hex"]))


def main(args) -> int:
    try:
        script = load_script(args.script)
    except ScriptError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if args.out:  # (found out only after the session, its summary lost, before)
        try:
            with open(args.out, "a"):
                pass
        except OSError as e:
            print(f"error: --out {args.out}: {e.strerror or e}", file=sys.stderr)
            return 2
    bus = open_bus(args.url)
    p = LockstepParticipant(bus, args.name, clock_timeout=args.clock_timeout)
    player = ScriptPlayer(p, script)
    r = p.run()
    p.close()
    if args.out:
        Path(args.out).write_text(json.dumps({"states": player.states, "replies": player.replies,
                                              "last_state": state_dict(player.last_msg) if player.last_msg else None}))
    ok, error = r.ok, r.error
    if ok and player.steps:  # (the session was shorter than the script: it did not do what it says)
        ok, error = False, (f"{len(player.steps)} step(s) not played: the session ended at sim time "
                            f"{r.sim_time_ns * 1e-9:.3f} s, before the step at {player.steps[0]['at_s']} s")
        print(f"error: sim-script: {error}", file=sys.stderr)
    print(json.dumps({"ok": ok, "error": error, "frames": r.frames, "sim_time_s": r.sim_time_ns * 1e-9,
                      "digest": r.digest_hex, "replies": len(player.replies),
                      "rejected": sum(1 for x in player.replies if not x["accepted"]), "bad_input": player.bad,
                      "steps_left": len(player.steps)}), flush=True)
    return 0 if ok else 1
