"""The simulated gripper: one CANopen node (canopen's LocalNode) with the CiA 402 drive
profile and the EDS in deploy/can/skillbus_gripper.eds, speaking exactly the frames a
real CANopen gripper speaks. Two ways to run:

* standalone: an internal finger model stepped on a wall-clock timer (tests of the
  driver without the physics server);
* ``--lockstep``: a lockstep participant whose fingers are the physics server's: each
  set-point becomes a sim_gripper_cmd_t, width and force come back in sim_state_t, and
  everything it sends (TPDO, heartbeat, EMCY) is driven by sim frames, never by timers.

    skillbus gripper-device --channel gripper0 --node-id 5 [--object-width 40000]
    skillbus gripper-device --channel gripper0 --node-id 5 --lockstep --name gripper

Reads RPDO1 (controlword, target position); sends boot-up, heartbeat, TPDO1
(statusword, position, grip state) every step, EMCY on faults; answers SDO.
Units: positions in micrometres of opening width, force limit in 0.1 N (object 0x6073).
"""

from __future__ import annotations

import json
import logging
import struct
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import canopen

from skillbus.can import cia402 as c

log = logging.getLogger("gripper-device")
EDS = Path(__file__).resolve().parents[3] / "deploy" / "can" / "skillbus_gripper.eds"
MAX_WIDTH_UM = 80_000
RATED_FORCE = 400            # 40 N: above this, a long block is an over-current fault
BLOCKED_TIMEOUT_S = 1.0


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
AT_TARGET_UM = 500


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

    def on_state(self, width_m: float, force_n: float, touching: set[str], width_target_m: float | None = None) -> None:
        self.width, self.force, self.touching = width_m * 1e6, force_n, touching
        # Force and contacts say something about this move only once the physics has it.
        self.acknowledged = width_target_m is None or abs(width_target_m * 1e6 - self.target) < 1.0

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
        self.acknowledged = False
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
        # following error: behind the commanded profile by more than the window
        d = self.target - self._start
        planned = self._start + max(-abs(d), min(abs(d), self.velocity * self._elapsed)) * (1 if d >= 0 else -1)
        behind = abs(planned - self.width) > FOLLOWING_WINDOW_UM
        self._lagging = self._lagging + dt if behind else 0.0

    def following_error(self) -> bool:
        return self.moving and self._lagging > FOLLOWING_TIMEOUT_S


class GripperDevice:
    def __init__(self, network: canopen.Network, node_id: int, eds: str | Path = EDS,
                 object_width: float | None = None, fingers: FingerModel | SimFingers | None = None) -> None:
        self.node = canopen.LocalNode(node_id, str(eds))
        network.add_node(self.node)
        self.network = network
        self.model = fingers if fingers is not None else FingerModel(object_width=object_width)
        self.state = c.SWITCH_ON_DISABLED
        self.controlword = 0
        self.error_code = 0
        self.was_gripped = False
        self.rpdo_errors = 0
        self.lock = threading.Lock()
        self.node.rpdo.read(from_od=True)
        self.node.rpdo[1].add_callback(self._on_rpdo)
        self.node.tpdo.read(from_od=True)
        network.subscribe(self.node.rpdo[1].cob_id, self._check_rpdo_length)

    # -- CAN side --------------------------------------------------------------------
    def boot(self) -> None:
        self.node.nmt.send_command(0x81)  # reset node: boot-up message
        self.node.nmt.send_command(0x80)  # pre-operational: the heartbeat starts (0x1017)

    def _check_rpdo_length(self, can_id: int, data: bytearray, timestamp: float) -> None:
        if len(data) != 6:
            self.rpdo_errors += 1  # CiA 301: a PDO of the wrong length is not processed
            log.warning("RPDO1 of %d bytes (6 expected) ignored", len(data))

    def _on_rpdo(self, pdo) -> None:
        if len(pdo.data) != 6:
            return
        cw = pdo["Controlword"].raw
        target = pdo["Target position"].raw
        with self.lock:
            self._controlword(cw, target)
        self._publish_status()  # the answer to a set-point does not wait for the next step

    def _controlword(self, cw: int, target: int) -> None:
        rising = cw & ~self.controlword
        self.controlword = cw
        if self.state == c.FAULT:
            if rising & c.CW_FAULT_RESET:
                self.state, self.error_code = c.SWITCH_ON_DISABLED, 0
                self.node.sdo[0x603F].raw = 0
                self.node.sdo[0x1001].raw = 0
            return
        low = cw & 0x008F
        if low & 0x0007 == 0x0006 and self.state in (c.SWITCH_ON_DISABLED, c.SWITCHED_ON, c.OPERATION_ENABLED):
            self.state = c.READY_TO_SWITCH_ON
        elif low & 0x000F == 0x0007 and self.state in (c.READY_TO_SWITCH_ON, c.OPERATION_ENABLED):
            self.state = c.SWITCHED_ON
        elif low & 0x000F == 0x000F and self.state in (c.SWITCHED_ON, c.OPERATION_ENABLED):
            self.state = c.OPERATION_ENABLED
        if self.state == c.OPERATION_ENABLED:
            if cw & c.CW_HALT:
                self.model.halt()
            elif rising & c.CW_NEW_SET_POINT:
                self.model.move_to(max(0, min(MAX_WIDTH_UM, target)), self.node.sdo[0x6081].raw or 1,
                                   self.node.sdo[0x6073].raw)
                self.was_gripped = False

    def _fault(self, code: int) -> None:
        self.state, self.error_code = c.FAULT, code
        self.model.fault_stop()
        self.node.sdo[0x603F].raw = code
        self.node.sdo[0x1001].raw = 0x01  # generic error
        self.node.emcy.send(code, 0x01, struct.pack("<I", int(self.model.width))[:5].ljust(5, b"\0"))
        log.warning("fault 0x%04X: %s", code, c.EMCY_TEXT.get(code, ""))

    # -- the simulation ------------------------------------------------------------------
    def grip_state(self) -> int:
        g = 0
        if self.model.moving and not self.model.in_contact:
            g |= c.GRIP_MOVING
        if not self.model.moving or self.model.in_contact:
            g |= c.GRIP_REACHED
        if self.model.in_contact:
            g |= c.GRIP_GRIPPED
            self.was_gripped = True
        elif self.was_gripped and self.model.moving:
            g |= c.GRIP_LOST  # it held an object and is closing on nothing now
        return g

    def step(self, dt: float) -> None:
        """One step of the fingers, then TPDO1 (the event timer of its transmission)."""
        with self.lock:
            if self.state == c.OPERATION_ENABLED:
                self.model.step(dt)
                force = self.node.sdo[0x6073].raw
                if (self.model.moving and self.model.in_contact and force > RATED_FORCE
                        and self.model.blocked_for > BLOCKED_TIMEOUT_S):
                    self._fault(c.EMCY_OVER_CURRENT)
                elif self.model.following_error():
                    self._fault(c.EMCY_FOLLOWING_ERROR)
        self._publish_status(event=False)

    # Event timer of TPDO1 in steps: standalone every step (10 ms, the EDS's 0x1800sub5);
    # under lockstep the TPDO goes out on every change and otherwise every 10th frame.
    event_every = 1
    _since_sent = 0
    _last_sent: tuple | None = None

    def _publish_status(self, event: bool = True) -> None:
        """TPDO1 with the current state (event-driven, transmission type 255: at once
        when the state changes, and on the event timer)."""
        with self.lock:
            sw = c.STATE_WORDS[self.state] | c.SW_REMOTE
            grip = self.grip_state()
            if grip & c.GRIP_REACHED and self.state == c.OPERATION_ENABLED:
                sw |= c.SW_TARGET_REACHED
            if self.controlword & c.CW_NEW_SET_POINT:
                sw |= c.SW_SET_POINT_ACK
            tpdo = self.node.tpdo[1]
            tpdo["Statusword"].raw = sw
            tpdo["Position actual value"].raw = int(round(self.model.width))
            tpdo["Grip state"].raw = grip
            self.node.sdo[0x6041].raw = sw
            self.node.sdo[0x6064].raw = int(round(self.model.width))
            self.node.sdo[0x2000].raw = grip
            operational = self.node.nmt.state == "OPERATIONAL"
            now = (sw, int(round(self.model.width)), grip)
            self._since_sent += 1
            due = now != self._last_sent or self._since_sent >= self.event_every or event
            if operational and due:
                self._last_sent, self._since_sent = now, 0
        if operational and due:
            tpdo.transmit()


    def heartbeat_if_due(self, sim_time_ns: int) -> None:
        """Lockstep: the heartbeat producer (0x1017 ms of sim time) from the frames."""
        period_ms = self.node.sdo[0x1017].raw
        if period_ms <= 0 or self.node.nmt.state == "INITIALISING":
            return
        if self._next_heartbeat_ns is None or sim_time_ns >= self._next_heartbeat_ns:
            self.network.send_message(0x700 + self.node.id, [c.NMT_STATE_CODES[self.node.nmt.state]])
            self._next_heartbeat_ns = sim_time_ns + period_ms * 1_000_000

    _next_heartbeat_ns: int | None = None


def run_lockstep(args) -> int:
    """The device as a lockstep participant, its fingers those of the physics server."""
    import can

    from skillbus.bus import open_bus
    from skillbus.can.lockstep_link import LockstepCanLink, sdo_ids
    from skillbus.lockstep import LockstepParticipant
    from skillbus.msgs import decode, sim_state_t
    from skillbus.sim.messages import gripper_channel, state_channel

    bus = open_bus(args.url)
    p = LockstepParticipant(bus, args.name, kind="gripper-device")
    network = canopen.Network()
    link = LockstepCanLink(p, can.Bus(interface=args.interface, channel=args.channel), args.channel, network,
                           sdo_ids(args.node_id))
    fingers = SimFingers(lambda m: p.publish(gripper_channel(), m))
    dev = GripperDevice(network, args.node_id, args.eds or EDS, fingers=fingers)
    dev.event_every = 10
    bad = [0]

    raw: list[bytes | None] = [None]

    def on_state(m) -> None:
        raw[0] = m.data

    def take_state() -> None:
        # Decoded only while the fingers move or were just told to: at rest nothing in
        # the state can change what the device reports (it is the only one moving them).
        if raw[0] is None or not (fingers.moving or not fingers.acknowledged or last_state[0] is None):
            return
        s = decode(sim_state_t, raw[0])
        raw[0] = None
        if s is None:
            bad[0] += 1
            return
        last_state[0] = s
        fingers.on_state(s.finger_width, s.finger_force, {x.body_b for x in s.contacts}, s.finger_width_target)

    p.subscribe(state_channel(), on_state)
    last: list[int | None] = [None]
    last_state: list = [None]

    def on_frame(frame: int, sim_time_ns: int) -> None:
        if last[0] is None:
            dev.boot()  # boot-up in the first frame: nothing but SDO goes out before the run
        dt = (sim_time_ns - last[0]) * 1e-9 if last[0] is not None else 0.0
        last[0] = sim_time_ns
        take_state()
        dev.step(dt)
        dev.heartbeat_if_due(sim_time_ns)

    p.on_frame = link.wrap(on_frame)
    print(json.dumps({"node": args.node_id, "channel": args.channel, "lockstep": args.name}), flush=True)
    r = p.run()
    p.close()
    link.shutdown()
    print(json.dumps({"ok": r.ok, "error": r.error, "frames": r.frames, "digest": r.digest_hex,
                      "can_sent": link.stats["sent"], "can_received": link.stats["received"],
                      "rpdo_errors": dev.rpdo_errors, "bad_input": bad[0]}), flush=True)
    return 0 if r.ok else 1


def run_physics_wall_clock(args) -> int:
    """The device on the wall clock with the physics server's fingers (the physics server
    in wall-clock mode): CAN through canopen's notifier, frames from a local timer."""
    from skillbus.bus import open_bus
    from skillbus.lockstep import LockstepParticipant
    from skillbus.msgs import decode, sim_state_t
    from skillbus.sim.messages import gripper_channel, state_channel

    bus = open_bus(args.url)
    p = LockstepParticipant(bus, args.name, kind="gripper-device", wall_clock=True,
                            wall_frame_period_ns=int(args.period_ms * 1e6))
    network = canopen.Network()
    network.connect(interface=args.interface, channel=args.channel)
    fingers = SimFingers(lambda m: bus.publish(gripper_channel(), m.encode()))
    dev = GripperDevice(network, args.node_id, args.eds or EDS, fingers=fingers)

    def on_state(m) -> None:
        s = decode(sim_state_t, m.data)
        if s is not None:
            with dev.lock:
                fingers.on_state(s.finger_width, s.finger_force, {x.body_b for x in s.contacts}, s.finger_width_target)

    p.subscribe(state_channel(), on_state)
    dev.boot()
    print(json.dumps({"node": args.node_id, "channel": args.channel, "physics": True}), flush=True)
    p.on_frame = lambda frame, t: dev.step(args.period_ms / 1000.0)
    try:
        p.run()
    except KeyboardInterrupt:
        pass
    finally:
        network.disconnect()
    return 0


def main(args) -> int:
    logging.basicConfig(level=logging.INFO)
    if getattr(args, "lockstep", False):
        return run_lockstep(args)
    if getattr(args, "physics", False):
        return run_physics_wall_clock(args)
    network = canopen.Network()
    network.connect(interface=args.interface, channel=args.channel)
    dev = GripperDevice(network, args.node_id, args.eds or EDS, args.object_width)
    dev.boot()
    print(json.dumps({"node": args.node_id, "channel": args.channel}), flush=True)
    period = args.period_ms / 1000.0
    next_t = time.monotonic()
    try:
        while True:  # standalone: the finger model on a wall-clock timer
            next_t += period
            dev.step(period)
            time.sleep(max(0.0, next_t - time.monotonic()))
    except KeyboardInterrupt:
        pass
    finally:
        network.disconnect()
    return 0
