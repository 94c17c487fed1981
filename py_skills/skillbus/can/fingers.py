"""The fingers of the simulated gripper (skillbus.can.device), as the device sees them:

* :class:`FingerModel`: two fingers of its own that close toward a target width at a
  constant speed, stopped by an object between them (the standalone device, tests of the
  driver without the physics server);
* :class:`SimFingers`: the physics server's fingers: a set-point goes out as a
  sim_gripper_cmd_t, width, force and contacts come back in sim_state_t.

Both have the interface the device drives: ``width``, ``moving``, ``blocked_for``,
``in_contact``, ``step(dt)``, ``move_to(target, velocity, force_limit)``, ``halt()``,
``fault_stop()``, ``following_error()``. Units: micrometres of opening width, um/s,
force limit in 0.1 N (object 0x6073).
"""

from __future__ import annotations

from dataclasses import dataclass

from skillbus.validate import finite

MAX_WIDTH_UM = 80_000
# A measured width may overshoot the travel a little (pads pressed together, a joint at
# its limit); a width further outside is not a measurement of these fingers.
WIDTH_SLACK_UM = 5_000
# The largest force limit 0x6073 can hold (U16 in 0.1 N): no force of these fingers is
# larger, in either direction.
MAX_FORCE_N = 0xFFFF / 10


@dataclass
class FingerModel:
    """Two fingers that close toward a target width, stopped by an object between them."""
    width: float = MAX_WIDTH_UM
    target: float = MAX_WIDTH_UM
    velocity: float = 50_000          # um/s
    object_width: float | None = None
    moving: bool = False
    blocked_for: float = 0.0

    def step(self, dt: float) -> None:
        if not self.moving:
            return
        stop_at = self.target
        if self.object_width is not None and self.target < self.object_width <= self.width + 1e-9:
            stop_at = self.object_width  # the object stops the fingers
        delta = stop_at - self.width
        move = max(-self.velocity * dt, min(self.velocity * dt, delta))
        self.width += move
        if abs(stop_at - self.width) < 1e-6:
            self.width = stop_at
            if stop_at == self.target:
                self.moving = False
            else:
                self.blocked_for += dt

    @property
    def in_contact(self) -> bool:
        return self.object_width is not None and abs(self.width - self.object_width) < 1e-6 and \
            self.target < self.object_width

    def move_to(self, target: float, velocity: float, force_limit: int) -> None:
        self.target, self.velocity = target, velocity
        self.moving, self.blocked_for = True, 0.0

    def halt(self) -> None:
        self.target, self.moving = self.width, False

    def fault_stop(self) -> None:
        self.moving, self.blocked_for = False, 0.0

    def following_error(self) -> bool:
        return False  # the internal model always follows


FOLLOWING_WINDOW_UM = 5_000      # 0x6065 semantics: the fingers may lag the profile this much
FOLLOWING_TIMEOUT_S = 0.2
# A physics whose time has not moved for this long (the device's own time) while the
# fingers should move is a motor that does not turn: a following error too (a physics
# that is only slow is not; see SimFingers.step).
FROZEN_PHYSICS_S = 1.0
AT_TARGET_UM = 500


def sim_state_reading(s) -> tuple[float, float, set[str], float, float | None]:
    """What SimFingers.on_state takes from a sim_state_t (the physics server's ground
    truth), checked before any of it is used: width and target between
    closed and fully open (with WIDTH_SLACK_UM), the force within MAX_FORCE_N, all finite.
    Raises skillbus.validate.BadValue naming the first bad field: an infinite width used
    as it came killed the device (OverflowError making it micrometres), a NaN or a width
    of 1e300 likewise, a negative one made it report nonsense."""
    lo, hi = -WIDTH_SLACK_UM * 1e-6, (MAX_WIDTH_UM + WIDTH_SLACK_UM) * 1e-6
    width = finite(s.finger_width, "finger_width", lo, hi)
    force = finite(s.finger_force, "finger_force", -MAX_FORCE_N, MAX_FORCE_N)
    target = finite(s.finger_width_target, "finger_width_target", lo, hi)
    sim_time = s.header.sim_time_ns * 1e-9 if s.header.sim_time_ns >= 0 else None
    return width, force, {c.body_b for c in s.contacts}, target, sim_time


class SimFingers:
    """The physics server's fingers. A set-point goes out as a sim_gripper_cmd_t; width,
    force and finger-object contacts come back every frame in sim_state_t. The fingers
    are stalled when they push with (nearly) the force limit short of the target; an
    object is gripped when they are stalled on an object they touch."""

    def __init__(self, publish) -> None:
        self.publish = publish            # publish(sim_gripper_cmd_t) for this frame
        self.width = float(MAX_WIDTH_UM)
        self.target = float(MAX_WIDTH_UM)
        self.velocity = 50_000.0
        self.force_limit_n = 20.0
        self.force = 0.0
        self.touching: set[str] = set()
        self.moving = False
        self.blocked_for = 0.0
        self._start, self._elapsed, self._lagging = self.width, 0.0, 0.0
        self._commands = 0
        self.acknowledged = True
        self._sim_now: float | None = None    # the physics' time of its last state, s
        self._sim_start: float | None = None  # ... when it took the set-point of this move
        self._sim_seen: float | None = None   # ... at the last step, and how long it has stood still
        self._frozen_for = 0.0

    def on_state(self, width_m: float, force_n: float, touching: set[str], width_target_m: float | None = None,
                 sim_time_s: float | None = None) -> None:
        self.width, self.force, self.touching = width_m * 1e6, force_n, touching
        # Force and contacts say something about this move only once the physics has it.
        was = self.acknowledged
        self.acknowledged = width_target_m is None or abs(width_target_m * 1e6 - self.target) < 1.0
        self._sim_now = sim_time_s
        if self.acknowledged and not was:
            self._sim_start = sim_time_s

    def _send(self, target: float) -> None:
        from skillbus.sim.messages import gripper_command
        self._commands += 1
        self.publish(gripper_command(f"can-{self._commands}", target * 1e-6, max(self.velocity, 1.0) * 1e-6,
                                     self.force_limit_n))

    def move_to(self, target: float, velocity: float, force_limit: int) -> None:
        self.target, self.velocity = float(target), float(velocity)
        self.force_limit_n = max(0.1, force_limit / 10.0)
        self.moving, self.blocked_for = True, 0.0
        self._start, self._elapsed, self._lagging = self.width, 0.0, 0.0
        self.acknowledged, self._sim_start = False, None
        self._send(self.target)

    def halt(self) -> None:
        self.target, self.moving = self.width, False
        self._send(self.width)

    def fault_stop(self) -> None:
        self.halt()
        self.blocked_for = 0.0

    @property
    def stalled(self) -> bool:
        return (self.acknowledged and abs(self.width - self.target) > AT_TARGET_UM
                and self.force >= 0.9 * self.force_limit_n)

    @property
    def in_contact(self) -> bool:
        return self.stalled and bool(self.touching)

    def step(self, dt: float) -> None:
        if not self.moving:
            return
        self._elapsed += dt
        if not self.acknowledged:
            return  # the physics has not taken the set-point yet
        if abs(self.width - self.target) <= AT_TARGET_UM:
            self.moving = False
            return
        if self.stalled:
            self.blocked_for += dt
            return
        # following error: behind the commanded profile by more than the window. The
        # profile runs in the physics' time from when it took the set-point: on the wall
        # clock a loaded machine slows the physics below real time, and fingers that move
        # as fast as the physics lets them are not behind (they were, in the device's own
        # time, and a busy machine faulted the gripper).
        elapsed = self._elapsed
        if self._sim_start is not None and self._sim_now is not None:
            elapsed = max(0.0, self._sim_now - self._sim_start)
        if self._sim_now is not None and self._sim_now == self._sim_seen:
            self._frozen_for += dt
        else:
            self._sim_seen, self._frozen_for = self._sim_now, 0.0
        d = self.target - self._start
        planned = self._start + max(-abs(d), min(abs(d), self.velocity * elapsed)) * (1 if d >= 0 else -1)
        behind = abs(planned - self.width) > FOLLOWING_WINDOW_UM or self._frozen_for > FROZEN_PHYSICS_S
        self._lagging = self._lagging + dt if behind else 0.0

    def following_error(self) -> bool:
        return self.moving and self._lagging > FOLLOWING_TIMEOUT_S
