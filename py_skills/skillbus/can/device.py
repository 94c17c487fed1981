"""The simulated gripper: one CANopen node (canopen's LocalNode) with the CiA 402 drive
profile and the EDS in deploy/can/skillbus_gripper.eds, speaking exactly the frames a
real CANopen gripper speaks. The node is :class:`GripperDevice`; its fingers are a model
(skillbus.can.fingers); a runner steps it:

* standalone (skillbus.can.device_standalone): the internal finger model stepped on a
  wall-clock timer (tests of the driver without the physics server);
* ``--physics`` (skillbus.can.device_physics): on the wall clock, with the physics
  server's fingers (the physics server in wall-clock mode);
* ``--lockstep`` (skillbus.can.device_lockstep): a lockstep participant whose fingers are
  the physics server's: each set-point becomes a sim_gripper_cmd_t, width and force come
  back in sim_state_t, and everything it sends (TPDO, heartbeat, EMCY) is driven by sim
  frames, never by timers.

    skillbus gripper-device --channel gripper0 --node-id 5 [--object-width 40000]
    skillbus gripper-device --channel gripper0 --node-id 5 --lockstep --name gripper

Reads RPDO1 (controlword, target position); sends boot-up, heartbeat, TPDO1
(statusword, position, grip state) every step, EMCY on faults; answers SDO.
Units: positions in micrometres of opening width, force limit in 0.1 N (object 0x6073).
"""

from __future__ import annotations

import logging
import struct
import sys
import threading
from pathlib import Path

import can
import canopen

from skillbus.can import cia402 as c
from skillbus.can.eds import EDS, TPDO1_FIELDS  # noqa: F401  (EDS: also the runners' import)
from skillbus.can.fingers import (AT_TARGET_UM, MAX_FORCE_N, MAX_WIDTH_UM, WIDTH_SLACK_UM, FingerModel, SimFingers,
                                  sim_state_reading)
from skillbus.can.pdo_codec import PdoCodec
from skillbus.validate import BadValue, Rejects, integer, one_of

log = logging.getLogger("gripper-device")
RATED_FORCE = 400            # 40 N: above this, a long block is an over-current fault
BLOCKED_TIMEOUT_S = 1.0
MAX_VELOCITY_UM_S = 200_000  # 0x6081: the fingers' top speed (the physics server refuses faster)
SDO_VALUE_RANGE = 0x06090030  # CiA 301 abort code: value range of parameter exceeded


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
        # Received values not acted on (skillbus.validate): SB_SIM_STATE fields, RPDO
        # set-points, SDO writes, frames of the wrong length; in the runners' summaries.
        self.rejects = Rejects("gripper-device")
        self.bus_down = False  # a wall-clock runner's sends fail (step_on_the_wall_clock)
        self.lock = threading.Lock()
        # Frames are handled one at a time, and not while the node boots (boot()).
        self._frames = threading.RLock()
        handle = network.notify
        # Frames canopen's handlers unpack without checking their length (a short one
        # raises inside them): the NMT command (2 bytes) and SDO requests (8 bytes,
        # CiA 301). Dropped and counted here, before canopen sees them.
        lengths = {0x000: 2, 0x600 + node_id: 8}

        def notify(can_id: int, data: bytearray, timestamp: float) -> None:
            want = lengths.get(can_id)
            if want is not None and len(data) != want:
                self.rejects.record(f"COB-ID 0x{can_id:03X}", BadValue("length", len(data), f"{want} bytes expected"))
                return
            with self._frames:
                handle(can_id, data, timestamp)

        network.notify = notify
        self.node.add_write_callback(self._check_sdo_write)
        self.node.rpdo.read(from_od=True)
        self.node.rpdo[1].add_callback(self._on_rpdo)
        self.node.tpdo.read(from_od=True)
        self._tpdo_codec = PdoCodec.of(self.node.tpdo[1], TPDO1_FIELDS)  # (None: canopen's own path)
        # The dictionary's entries of the status (what an SDO upload reads), written as an
        # SDO download to this node would write them, without the SDO layers.
        od = self.node.object_dictionary
        self._status_entries = [(index, od[index]) for index in (0x6041, 0x6064, 0x2000)]
        network.subscribe(self.node.rpdo[1].cob_id, self._check_rpdo_length)
        # The heartbeat's period (0x1017), read at every lockstep frame: kept here as it is
        # written (a read through the dictionary costs python-canopen several microseconds).
        # Registered last, so no later callback refuses a write this has already taken.
        self._heartbeat_ms = self.node.sdo[0x1017].raw
        # 0x2001 likewise; an EDS without it (one written before it was added) keeps sending
        # every change, as the device did then.
        self._position_delta = self.node.sdo[0x2001].raw if 0x2001 in self.node.object_dictionary else 0
        self._force_limit = self.node.sdo[0x6073].raw  # (0x6073, read by finger_watch at every frame holding)
        self.node.add_write_callback(self._note_written)

    # -- CAN side --------------------------------------------------------------------
    def boot(self) -> None:
        """The boot-up message, then pre-operational with the heartbeat running. No frame
        is handled in between: canopen's node sends the boot-up while still initialising,
        and a driver that answers it at once (configuring 0x1017 by SDO) would otherwise
        start a second heartbeat task carrying the boot-up's state 0, never stopped."""
        with self._frames:
            self.node.nmt.send_command(0x81)  # reset node: boot-up message
            self.node.nmt.send_command(0x80)  # pre-operational: the heartbeat starts (0x1017)

    def _check_rpdo_length(self, can_id: int, data: bytearray, timestamp: float) -> None:
        if len(data) != 6:
            self.rpdo_errors += 1  # CiA 301: a PDO of the wrong length is not processed
            log.warning("RPDO1 of %d bytes (6 expected) ignored", len(data))

    # Objects whose value the device acts on, with what it can do: anything else written
    # by SDO is refused with abort 0x06090030 (as a real drive refuses a value out of
    # range) and counted. Their types bound the rest (U16, U32).
    SDO_RANGES = {0x6060: ("modes of operation", (1,)),                 # profile position only
                  0x6073: ("force limit", range(1, 0xFFFF + 1)),       # 0 would grip with no force
                  0x6081: ("profile velocity", range(1, MAX_VELOCITY_UM_S + 1)),
                  0x2001: ("TPDO1 position delta", range(0, MAX_WIDTH_UM + 1))}

    def _check_sdo_write(self, index: int, subindex: int, od, data: bytes) -> None:
        rule = self.SDO_RANGES.get(index)
        if rule is None:
            return
        name, allowed = rule
        value = od.decode_raw(data)
        try:
            if isinstance(allowed, range):
                integer(value, name, allowed.start, allowed.stop - 1)
            else:
                one_of(value, name, allowed)
        except BadValue as e:
            self.rejects.record(f"SDO 0x{index:04X}", e)
            raise canopen.SdoAbortedError(SDO_VALUE_RANGE) from None

    def _note_written(self, index: int, subindex: int, od, data: bytes) -> None:
        """Keeps the objects read every lockstep frame (0x1017, 0x2001, 0x6073) as they are written."""
        if index == 0x1017 and subindex == 0:
            self._heartbeat_ms = od.decode_raw(data)
        elif index == 0x6073 and subindex == 0:
            self._force_limit = od.decode_raw(data)
        elif index == 0x2001 and subindex == 0:
            self._position_delta = od.decode_raw(data)

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
                # The target is checked only here, where it is used: the enable sequence
                # carries whatever position the driver last saw, which may be a little
                # outside the travel. A set-point outside it is not moved to.
                try:
                    target = integer(target, "target position", 0, MAX_WIDTH_UM)
                except BadValue as e:
                    self.rejects.record("RPDO1", e)
                    return
                self.model.move_to(target, self.node.sdo[0x6081].raw or 1, self.node.sdo[0x6073].raw)
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
                # (the force limit read only when it can matter: an object-dictionary read
                # costs python-canopen about 4 us, and this runs every frame)
                if (self.model.moving and self.model.in_contact and self.model.blocked_for > BLOCKED_TIMEOUT_S
                        and self._force_limit > RATED_FORCE):
                    self._fault(c.EMCY_OVER_CURRENT)
                elif self.model.following_error():
                    self._fault(c.EMCY_FOLLOWING_ERROR)
        self._publish_status(event=False)

    # Event timer of TPDO1 in steps: standalone every step (10 ms, the EDS's 0x1800sub5);
    # under lockstep the TPDO goes out on every change of state (statusword, grip state)
    # or of the position by at least 0x2001, and otherwise every 10th frame.
    event_every = 1
    _since_sent = 0
    _last_sent: tuple | None = None
    _last_written: tuple | None = None  # (statusword, width, grip state) in the dictionary

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
            now = (sw, int(round(self.model.width)), grip)
            if now != self._last_written:
                # The dictionary's entries (what an SDO upload reads; read-only for others)
                # only those that changed: each write costs python-canopen several
                # microseconds and its write callbacks; at rest nothing changes for
                # hundreds of frames, and holding an object only the width does.
                before = self._last_written or (None, None, None)
                for (index, var), value, was in zip(self._status_entries, now, before):
                    if value != was:
                        self.node.set_data(index, 0, var.encode_raw(value))
                self._last_written = now
            operational = self.node.nmt.state == "OPERATIONAL"
            self._since_sent += 1
            due = event or self._since_sent >= self.event_every or self._changed_enough(now)
            if operational and due:
                self._last_sent, self._since_sent = now, 0
                # TPDO1's contents before every send, changed or not: python-canopen takes a
                # frame that arrives with TPDO1's COB-ID (a rogue node's) into the map's
                # buffer, and it would go out as ours.
                if self._tpdo_codec is not None:
                    self._tpdo_codec.write(tpdo, now)
                else:
                    tpdo["Statusword"].raw = sw
                    tpdo["Position actual value"].raw = now[1]
                    tpdo["Grip state"].raw = grip
        if operational and due:
            tpdo.transmit()


    def _changed_enough(self, now: tuple[int, int, int]) -> bool:
        """Whether the status `now` (statusword, position, grip state) is news since the last
        TPDO1: a new statusword or grip state, or a position at least 0x2001 (µm) from the
        one sent. Holding an object the fingers move by a few to tens of micrometres from
        frame to frame as the arm carries it; each of those TPDOs woke three processes
        (this one, the CAN hub, the driver's) for a width nobody reads that finely: the
        grip itself is in the grip state, which always goes out at once."""
        last = self._last_sent
        if last is None or now[0] != last[0] or now[2] != last[2]:
            return True
        return abs(now[1] - last[1]) >= max(1, self._position_delta)

    def finger_watch(self) -> tuple | None:
        """Lockstep, holding an object: the bounds the physics' next states must keep for
        the next frames to do nothing but count towards TPDO1's event timer and the time
        blocked (common/python/finger_watch.hpp: width and set-point readable, the force
        pushing with at least 0.9 of the limit, TPDO1's position within 0x2001 of the one
        sent, the set-point taken and not reached; a contact). None unless the fingers are
        stalled on an object they grip, in operation, after a TPDO1, with a force limit at
        which no block can become an over-current fault."""
        with self.lock:
            m = self.model
            if (self.state != c.OPERATION_ENABLED or not isinstance(m, SimFingers) or not m.moving
                    or not m.in_contact or self._last_sent is None or self._since_sent >= self.event_every):
                return None
            if self._force_limit > RATED_FORCE:
                return None  # (its block would become an over-current fault after BLOCKED_TIMEOUT_S)
            sent, delta = self._last_sent[1], max(1, self._position_delta)
            lo, hi = -WIDTH_SLACK_UM * 1e-6, (MAX_WIDTH_UM + WIDTH_SLACK_UM) * 1e-6  # (sim_state_reading's)
            return (lo, hi, 0.9 * m.force_limit_n, MAX_FORCE_N, sent - delta + 1, sent + delta - 1, m.target,
                    float(AT_TARGET_UM))

    def quiet_horizon(self, frame: int) -> tuple[int, int] | None:
        """Lockstep, after `frame`'s step with the fingers at rest (or holding an object,
        with finger_watch's bounds kept): how far the next frames would do nothing but
        count towards TPDO1's event timer, given no CAN frame and no move (the last frame
        before the timer's TPDO, the sim time of the next heartbeat); None when the next
        frame may do something."""
        with self.lock:
            if self.model.moving and not self.model.in_contact:
                return None
            quiet = self.event_every - self._since_sent - 1
        if quiet < 1:
            return None
        heartbeat = 2**63 - 1
        if self._heartbeat_ms > 0 and self.node.nmt.state != "INITIALISING":
            if self._next_heartbeat_ns is None:
                return None
            heartbeat = self._next_heartbeat_ns
        return frame + quiet, heartbeat

    def frames_passed(self, n: int) -> None:
        """`n` frames acked within quiet_horizon without a step: at rest each would only
        have counted towards the event timer."""
        with self.lock:
            self._since_sent += n

    def heartbeat_if_due(self, sim_time_ns: int) -> None:
        """Lockstep: the heartbeat producer (0x1017 ms of sim time) from the frames."""
        period_ms = self._heartbeat_ms
        if period_ms <= 0 or self.node.nmt.state == "INITIALISING":
            return
        if self._next_heartbeat_ns is None or sim_time_ns >= self._next_heartbeat_ns:
            self.network.send_message(0x700 + self.node.id, [c.NMT_STATE_CODES[self.node.nmt.state]])
            self._next_heartbeat_ns = sim_time_ns + period_ms * 1_000_000

    _next_heartbeat_ns: int | None = None


def take_sim_state(dev: GripperDevice, fingers: SimFingers, s, where: str) -> bool:
    """Gives `fingers` the physics server's state `s` (a decoded sim_state_t from `where`,
    SB_SIM_STATE) if its values are sane (fingers.sim_state_reading); otherwise counts it
    in dev.rejects and keeps the last good state. True when taken."""
    try:
        reading = sim_state_reading(s)
    except BadValue as e:
        dev.rejects.record(where, e)
        return False
    with dev.lock:
        fingers.on_state(*reading)
    return True


def summary(dev: GripperDevice, bad_input: int = 0, **more) -> dict:
    """The device's counts for a runner's JSON summary: frames and values it did not act on
    (`bad_input`: the runner's own, e.g. states that did not decode, plus dev.rejects)."""
    return {**more, "rpdo_errors": dev.rpdo_errors, "bad_input": bad_input + dev.rejects.total,
            "rejected": dev.rejects.summary()}


def step_on_the_wall_clock(dev: GripperDevice, dt: float) -> None:
    """One step of a wall-clock runner: a bus that is gone (the virtual bus's hub
    restarting; its client reconnects by itself) loses this step's TPDO and is logged
    once, instead of ending the device. Not under lockstep: there a lost frame is an
    error of the run."""
    try:
        dev.step(dt)
    except can.CanError as e:
        if not dev.bus_down:
            log.warning("CAN send failed, the device goes on: %s", e)
        dev.bus_down = True
        return
    if dev.bus_down:
        log.info("CAN sends work again")
        dev.bus_down = False


def ignored_option(args) -> str:
    """Why an option the chosen runner would ignore without a word is refused, or ""."""
    lockstep, physics = getattr(args, "lockstep", False), getattr(args, "physics", False)
    if lockstep and physics:
        return ("--lockstep and --physics: one or the other (--lockstep: in frames with the physics server; "
                "--physics: on the wall clock with it)")
    if lockstep and getattr(args, "period_ms", None) is not None:
        return "--period-ms is for the wall clock: under --lockstep the frames step the device"
    if (lockstep or physics) and getattr(args, "object_width", None) is not None:
        return "--object-width is for the standalone device: with the physics server its objects are between the fingers"
    return ""


def main(args) -> int:
    """``skillbus gripper-device``: the runner its options ask for."""
    logging.basicConfig(level=logging.INFO)
    lockstep = getattr(args, "lockstep", False)
    refused = ignored_option(args)
    if refused:
        print(f"error: gripper-device: {refused}", file=sys.stderr)
        return 2
    if getattr(args, "period_ms", None) is None:
        args.period_ms = 10.0
    if lockstep:
        from skillbus.can import device_lockstep as runner
    elif getattr(args, "physics", False):
        from skillbus.can import device_physics as runner
    else:
        from skillbus.can import device_standalone as runner
    return runner.run(args)
