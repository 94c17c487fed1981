"""The arm of a skill process (``skills-process --arm``): the arm's state as its driver
publishes it (robot_arm_state_t on SB_ROBOT_ARM_STATE), trajectories out
(robot_arm_cmd_t on SB_ROBOT_ARM_CMD, answered by robot_cmd_reply_t on
SB_ROBOT_CMD_REPLY), and motion planning by the motion service (RPC area MOTION). The
driver is the physics server or a real arm's: this module cannot tell them apart (it
never imports skillbus.sim nor reads the simulator's channels).

Under lockstep the state is a lockstep subscription (a tick of frame n sees the state of
frame n) and commands are lockstep publications (from a tick of frame n they go out in
frame n + 1). On the wall clock both go straight over the bus.
"""

from __future__ import annotations

import logging
import time

from skillbus import tick_context
from typing import Any

from skillbus.bus import Bus
from skillbus.msgs import (decode, joint_traj_point_t, motion_plan_t, motion_request_t, robot_arm_state_t,
                           robot_cmd_reply_t)
from skillbus.robot.arm_state_decode import decode_arm_state
from skillbus.robot.messages import (arm_cmd_channel, arm_command, arm_state_channel, check_arm_state, reply_channel,
                                     traj_point)
from skillbus.rpc import RpcClient
from skillbus.validate import BadValue, Rejects

log = logging.getLogger("arm")


class ArmError(RuntimeError):
    pass


class Arm:
    # A plan is asked for inside a skill's tick: the call must end (and name the motion
    # service) well before the manager's tick timeout (2 s in the system) names the skill
    # process. Under lockstep the tick may wait for the process's frame before it starts:
    # 1.5 s left too little of the 2 s on a loaded machine. A plan takes milliseconds.
    def __init__(self, bus: Bus, participant: Any = None, name: str = "arm", motion_timeout: float = 1.5) -> None:
        self.bus, self.participant = bus, participant
        self.motion = RpcClient(bus, "MOTION", name)
        self.motion_timeout = motion_timeout
        self._state: robot_arm_state_t | None = None
        self._raw: bytes | None = None  # decoded only when a skill asks (ticks are rarer than frames)
        self.replies: dict[str, robot_cmd_reply_t] = {}
        self._ends: dict[str, float] = {}  # a trajectory's end at the earliest, by command id (execute)
        self.bad = 0  # messages not used: not decodable, or values not sane (by kind: rejects)
        self.rejects = Rejects("arm")
        if participant is not None:
            # (only the newest state is read: frames with nothing else for this process are
            # acked without the interpreter, skillbus.quiet_frames)
            participant.subscribe(arm_state_channel(), lambda m: self._on_state(m.data), latest_only=True)
            participant.subscribe(reply_channel(), lambda m: self._on_reply(m.data))
        else:
            bus.subscribe(arm_state_channel(), lambda ch, d: self._on_state(d))
            bus.subscribe(reply_channel(), lambda ch, d: self._on_reply(d))

    STALE_S = 0.5  # wall clock: a driver publishes its state every frame (10-20 ms)

    def _on_state(self, data: bytes) -> None:
        self._raw = data
        if self.participant is None:
            self._heard = time.monotonic()  # liveness only (wall clock), never behaviour under lockstep

    def silence(self) -> str:
        """On the wall clock: why the arm's driver looks gone ("" while its state keeps
        coming). Under lockstep a driver that dies ends the session, so it is always ""."""
        if self.participant is not None:
            return ""
        heard = getattr(self, "_heard", None)
        if heard is None:
            return f"no robot arm state on {arm_state_channel()} yet (is the physics server or the arm's driver running?)"
        # Silent up to the last moment this process had read everything that had come: a
        # process starved of the CPU under load heard nothing for a while, but the state
        # kept coming into its socket (that called a live driver silent).
        quiet = self.bus.caught_up_at() - heard
        if quiet > self.STALE_S:
            return (f"the robot arm's driver went silent: no state on {arm_state_channel()} for {quiet:.1f} s "
                    "(is the physics server or the arm's driver running?)")
        return ""

    @property
    def state(self) -> robot_arm_state_t | None:
        if self._raw is not None:
            s = decode_arm_state(self._raw)
            self._raw = None
            if s is None:
                self.bad += 1
                return self._state
            try:
                check_arm_state(s)  # before a skill plans from it (the last good state stays)
            except BadValue as e:
                self.bad += 1
                self.rejects.record(arm_state_channel(), e)
                return self._state
            self._state = s
        return self._state

    def _on_reply(self, data: bytes) -> None:
        r = decode(robot_cmd_reply_t, data)
        if r is None:
            self.bad += 1
            return
        if r.command == "arm":
            self.replies[r.id] = r
            while len(self.replies) > 1000:
                self.replies.pop(next(iter(self.replies)))

    # -- what the skills use ---------------------------------------------------
    def joint_names(self) -> list[str]:
        return list(self._need_state().joint_names)

    def joints(self) -> list[float]:
        return list(self._need_state().position)

    def _need_state(self) -> robot_arm_state_t:
        if self.state is None:
            raise ArmError(f"no arm state yet on {arm_state_channel()} (is the physics server or the arm's driver "
                           "running?)")
        return self.state

    def plan(self, target: list[float], cartesian: bool = False, speed_scale: float = 0.5,
             held: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> motion_plan_t:
        """A trajectory from the motion service. `held`: the sides (m) of a box the gripper
        holds, which the service keeps clear of obstacles as it does the arm."""
        req = motion_request_t()
        req.joint_names = self.joint_names()
        req.num_joints = len(req.joint_names)
        req.start = self.joints()
        req.target = [float(x) for x in target]
        req.cartesian, req.step_m, req.speed_scale = cartesian, 0.01, speed_scale
        req.held = [float(x) for x in held]
        # The frame a motion service run with --map asks the occupancy map as of (it answers
        # once it has finished that frame: a cloud inserted at this frame may take seconds).
        tick = tick_context.current_tick()
        req.as_of_frame = tick.frame if tick is not None else (
            self.participant.frame if self.participant is not None and self.participant.frame >= 0 else -1)
        return self.motion.call("plan", req, motion_plan_t, timeout=self.motion_timeout)

    def execute(self, plan: motion_plan_t, cmd_id: str) -> None:
        self._send(cmd_id, list(plan.joint_names), list(plan.points))
        if plan.points:  # (the robot starts it at the earliest now: it cannot end sooner)
            self._ends[cmd_id] = tick_context.now_s() + plan.points[-1].time_from_start_ns * 1e-9
            while len(self._ends) > 1000:
                self._ends.pop(next(iter(self._ends)))

    def not_done_before(self, cmd_id: str) -> float | None:
        """The time (s, tick_context.now_s()'s clock) before which `cmd_id`, a trajectory
        sent by execute(), cannot be finished: its last point's time from when it was sent.
        None until the robot has accepted it (a refusal comes at once and must be heard),
        and for a command of another kind. On the wall clock at most STALE_S / 2 from now,
        so that a driver that goes silent on the way is still named (silence())."""
        r = self.replies.get(cmd_id)
        end = self._ends.get(cmd_id)
        if r is None or not r.accepted or end is None:
            return None
        if self.participant is None:
            end = min(end, tick_context.now_s() + self.STALE_S / 2)
        return end

    def hold(self, cmd_id: str) -> list[float]:
        """Stops the arm where it is: a position target (one point at time 0) at the
        measured joint positions, which replaces the trajectory in progress. The physics
        server (like a robot driver's stop) brakes at once, within the joints' effort
        limits, and settles on that target; the arm ends within a few millimetres of
        where the state showed it (it brakes past it and comes back). Returns the
        target."""
        q = self.joints()
        self._send(cmd_id, self.joint_names(), [traj_point(0.0, q)])
        return q

    def send_joints(self, cmd_id: str, joint_names: list[str], points: list[joint_traj_point_t]) -> None:
        """Plays a joint trajectory of the caller's own (a joint-space target, no planning)."""
        self._send(cmd_id, joint_names, points)

    def _send(self, cmd_id: str, joint_names: list[str], points: list[joint_traj_point_t]) -> None:
        m = arm_command(cmd_id, joint_names, points)
        if self.participant is not None:
            self.participant.publish(arm_cmd_channel(), m)
        else:
            self.bus.publish(arm_cmd_channel(), m.encode())

    def finished(self, cmd_id: str, tolerance: float = 0.01) -> tuple[bool, str]:
        """(done, error): done when the arm has played `cmd_id` and settled; error when
        the robot rejected it."""
        r = self.replies.get(cmd_id)
        if r is not None and not r.accepted:
            return True, r.error
        s = self.state
        if s is None or s.arm_command_id != cmd_id:
            return False, ""
        return (not s.arm_moving and s.arm_tracking_error < tolerance), ""


def interface(bus: Bus, participant: Any = None, arg: str = "", **options: Any) -> Arm:
    """The arm interface (skillbus.robot.interfaces): the arm's state and commands over
    the robot's channels, planning by the motion service. `arg` is unused."""
    return Arm(bus, participant)


def arm() -> Arm:
    """The process's arm interface."""
    from skillbus.robot import interfaces
    try:
        return interfaces.get("arm", hint="--arm")
    except interfaces.InterfaceError as e:
        raise ArmError(str(e)) from None


def tool_pose() -> tuple[tuple[float, float, float], tuple[float, float, float, float]] | None:
    """The tool's world pose from the arm state (the robot's own joints, not a camera), or
    None in a process without an arm or before the first state."""
    try:
        state = arm().state
    except ArmError:
        return None
    if state is None:
        return None
    t = tuple(state.tool_pose)
    return (t[0], t[1], t[2]), (t[3], t[4], t[5], t[6])
