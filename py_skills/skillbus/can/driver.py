"""The gripper driver: a CANopen master for one CiA 402 gripper, on the `canopen` package
(no hand-packed frames). Configuration by SDO at start-up only; at run time PDOs:
RPDO1 (controlword, target position) out, TPDO1 (statusword, position, grip state) in.

Non-blocking after start(): command() sends a set-point, status() returns the latest
state; nothing waits inside a skill's tick. EMCY frames become faults with code and
text; malformed frames and values outside what the device can report (a position
beyond the travel, undefined grip bits, a heartbeat with no NMT state) are counted in
`malformed` (by kind in `rejects`) and logged once per kind, never used nor raised into
a skill.

Supervision (on the wall clock a thread of the driver's own, every heartbeat period / 5;
under lockstep advance() each frame, in sim time):
* no heartbeat for 3 periods: the fault "gripper node N: heartbeat lost at <time> (none
  for M ms)", until a heartbeat comes again;
* the bus gone (the virtual bus's hub, ``bus.fault``; a receive thread that died): the
  fault "CAN hub gone: <socket path>" instead (heartbeats cannot come then; their
  supervision starts afresh when the bus is back);
* the node's boot-up (COB-ID 0x700 + node, data 0x00) after start-up, or a heartbeat
  that says PRE-OPERATIONAL long after the NMT start (a boot-up missed while the bus was
  gone): the node was restarted. On the wall clock the thread configures it by SDO again,
  starts it and enables it (faults from before the restart are dropped); the status
  shows state "rebooted" meanwhile. Under lockstep that is a fault (configuration by SDO
  happens only before the run; a participant that dies ends the session anyway).

    driver = GripperDriver(network, node_id=5)
    driver.start()                    # boot-up, SDO configuration, NMT start, enable operation
    driver.command(width_um=0)        # close
    s = driver.status()               # s.state, s.position_um, s.gripped, s.fresh, s.faults ...

Under lockstep (a skill process's driver, its CAN traffic carried by a LockstepCanLink):
configure() by SDO before the run, then begin_startup() and, every frame, advance(sim
time) and snapshot(frame): the NMT start and the CiA 402 enable sequence proceed frame by
frame without waiting, the heartbeat is supervised in sim time, and a tick of frame n
sees the status as of frame n - 1 (the same on every run).
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import can
import canopen

from skillbus import tick_context
from skillbus.can import cia402 as c
from skillbus.can.eds import EDS, TPDO1_FIELDS
from skillbus.can.pdo_codec import PdoCodec
from skillbus.can.fingers import MAX_WIDTH_UM, WIDTH_SLACK_UM
from skillbus.validate import BadValue, Rejects, integer, one_of
from skillbus.waiting import WaitTimeout, wait_until

log = logging.getLogger("gripper-driver")
REBOOTED = "rebooted"  # the status's state from a node's boot-up until it is enabled again
GRIP_BITS = c.GRIP_MOVING | c.GRIP_REACHED | c.GRIP_GRIPPED | c.GRIP_LOST  # every bit 0x2000 defines


class GripperError(RuntimeError):
    pass


@dataclass
class GripperStatus:
    state: str = "unknown"
    statusword: int = 0
    position_um: int = 0
    grip: int = 0
    target_reached: bool = False
    faults: list[str] = field(default_factory=list)
    updates: int = 0
    fresh: bool = True   # it reflects the last command (a status from before it may still show the old move)

    @property
    def moving(self) -> bool:
        return bool(self.grip & c.GRIP_MOVING)

    @property
    def gripped(self) -> bool:
        return bool(self.grip & c.GRIP_GRIPPED)

    @property
    def lost(self) -> bool:
        return bool(self.grip & c.GRIP_LOST)


class GripperDriver:
    def __init__(self, network: canopen.Network, node_id: int, eds: str | Path = EDS, heartbeat_ms: int = 100,
                 velocity_um_s: int = 50_000, force_limit: int = 200, clock=time.monotonic,
                 max_width_um: int = MAX_WIDTH_UM) -> None:
        self.network, self.heartbeat_ms, self.clock = network, heartbeat_ms, clock
        self.max_width_um = max_width_um  # the gripper's travel: a position reported beyond it is not one
        self._startup: list[tuple[int, str]] | None = None  # lockstep start-up steps still to do
        self._startup_deadline = 0.0
        self._snapshots: dict[int, GripperStatus] = {}
        self._fresh_after: tuple[str, int] = ("updates", 0)
        self.lockstep = False  # set by begin_startup: frames, not arrivals, decide then
        self.velocity, self.force_limit = velocity_um_s, force_limit
        self.node = canopen.RemoteNode(node_id, str(eds))
        network.add_node(self.node)
        self._status = GripperStatus()
        self._lock = threading.Lock()
        self._last_heartbeat: float | None = None
        self._hb_fault: str | None = None    # while the heartbeat is lost
        self._bus_fault: str | None = None   # while the bus is gone
        self._started = False                # start-up done: a boot-up now means a restart
        self._operational_at: float | None = None  # when the NMT start went out
        self.restarts = self._restarts_handled = 0  # restarts of the node seen after start-up
        self._recovery_asked = False  # a command asked to clear a device fault (fault reset, enable)
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._supervisor: threading.Thread | None = None
        self._cw = 0
        self.malformed = 0  # frames not used: wrong length or values out of range (by kind: rejects)
        self.rejects = Rejects("gripper-driver")
        self._filter_frames(network, node_id)
        self.node.tpdo.read(from_od=True)
        self._tpdo_codec = PdoCodec.of(self.node.tpdo[1], TPDO1_FIELDS)  # (None: canopen's own reads)
        self.node.tpdo[1].add_callback(self._on_tpdo)
        self.node.rpdo.read(from_od=True)
        self.node.nmt.add_heartbeat_callback(self._on_heartbeat)
        self.node.emcy.add_callback(self._on_emcy)
        network.subscribe(self.node.tpdo[1].cob_id, self._check_tpdo_length)

    # -- incoming ---------------------------------------------------------------------------
    def _reject(self, where: str, error: BadValue) -> None:
        self.malformed += 1
        self.rejects.record(where, error)

    def _filter_frames(self, network: canopen.Network, node_id: int) -> None:
        """Drops (and counts) our node's frames that canopen's handlers would unpack without
        checking: a heartbeat is one byte holding an NMT state, an EMCY and an SDO answer
        are eight bytes (CiA 301). A short one raises inside canopen (on the wall clock its
        listener only logs that; under lockstep it would fail the frame), and a heartbeat
        with a state no node sends would count as the node being alive."""
        handle = network.notify
        heartbeat, lengths = 0x700 + node_id, {0x700 + node_id: 1, 0x80 + node_id: 8, 0x580 + node_id: 8}

        def notify(can_id: int, data: bytearray, timestamp: float) -> None:
            want = lengths.get(can_id)
            if want is not None:
                try:
                    integer(len(data), "length", want, want)
                    if can_id == heartbeat:
                        one_of(data[0] & 0x7F, "NMT state", sorted(c.NMT_STATE_CODES.values()))
                except BadValue as e:
                    self._reject(f"COB-ID 0x{can_id:03X}", e)
                    return
            handle(can_id, data, timestamp)

        network.notify = notify

    def _check_tpdo_length(self, can_id, data, timestamp) -> None:
        if len(data) != 7:
            self.malformed += 1
            log.warning("TPDO1 of %d bytes (7 expected) ignored", len(data))

    def _on_tpdo(self, pdo) -> None:
        if len(pdo.data) != 7:
            return
        if self._tpdo_codec is not None:
            statusword, position, grip = self._tpdo_codec.read(pdo.data)
        else:
            statusword, position, grip = (pdo[name].raw for name in TPDO1_FIELDS)
        try:
            # A position beyond the travel (with the slack a measurement may overshoot) or a
            # grip state with bits 0x2000 does not define is no status of this gripper:
            # the last good status stays.
            position = integer(position, "position actual value", -WIDTH_SLACK_UM, self.max_width_um + WIDTH_SLACK_UM)
            if grip & ~GRIP_BITS:
                raise BadValue("grip state", grip, f"bits outside 0x{GRIP_BITS:02X}")
        except BadValue as e:
            self._reject("TPDO1", e)
            return
        with self._lock:
            s = self._status
            s.statusword = statusword
            s.state = c.state_of(s.statusword)
            s.position_um = position
            s.grip = grip
            s.target_reached = bool(s.statusword & c.SW_TARGET_REACHED)
            s.updates += 1

    def _on_heartbeat(self, state: int) -> None:
        now = self.clock()
        self._last_heartbeat = now
        if not self._started:
            return  # the boot-up and heartbeats of the start-up
        period = self.heartbeat_ms / 1000.0
        if state == 0:
            why = "boot-up"
        elif (state == c.NMT_STATE_CODES["PRE-OPERATIONAL"] and self._operational_at is not None
              and now - self._operational_at > 3 * period and self.restarts == self._restarts_handled):
            why = "heartbeat PRE-OPERATIONAL"  # restarted while we could not hear its boot-up
        else:
            return
        with self._lock:
            self.restarts += 1
            self._operational_at = None
            self._hb_fault = None
            if self.lockstep:
                self._status.faults.append(
                    f"gripper node {self.node.id}: restarted ({why} at {self._time_label()}); not re-initialised "
                    f"under lockstep (its configuration by SDO is done only before the run)")
            else:
                self._status.faults.clear()  # a restarted node has none of its old faults
                self._status.state = REBOOTED
        log.warning("gripper node %d: %s at %s: it was restarted", self.node.id, why, self._time_label())
        self._wake.set()

    def _on_emcy(self, emcy) -> None:
        if emcy.code == 0:
            return  # error reset
        text = c.EMCY_TEXT.get(emcy.code, "device error")
        with self._lock:
            self._status.faults.append(f"EMCY 0x{emcy.code:04X}: {text}")
        log.error("gripper EMCY 0x%04X (%s), register 0x%02X", emcy.code, text, emcy.register)

    # -- start-up (may wait; never inside a tick) ----------------------------------------------------
    def start(self, timeout: float = 5.0) -> None:
        try:
            self.node.nmt.wait_for_heartbeat(timeout)
        except canopen.nmt.NmtError as e:
            raise GripperError(f"gripper node {self.node.id}: no heartbeat within {timeout} s ({e})") from None
        self._last_heartbeat = self.clock()
        self.configure()
        self._nmt_start()
        self.enable(timeout)
        self._started = True
        self.reinit_timeout = timeout
        self._supervisor = threading.Thread(target=self._supervise, name=f"gripper-{self.node.id}-supervisor",
                                            daemon=True)
        self._supervisor.start()

    def close(self) -> None:
        """Ends the wall-clock supervision (the network is the caller's to disconnect)."""
        self._stop.set()
        self._wake.set()
        if self._supervisor is not None and self._supervisor is not threading.current_thread():
            self._supervisor.join(timeout=10)

    def _nmt_start(self) -> None:
        self.node.nmt.state = "OPERATIONAL"
        self._operational_at = self.clock()

    def _supervise(self) -> None:
        """Wall clock: heartbeat and bus supervision, and re-initialisation of a node that
        was restarted (SDO and the enable sequence wait: here, never in a tick)."""
        period = min(0.02, max(0.005, self.heartbeat_ms / 5000.0))
        while not self._stop.is_set():
            self._wake.wait(period)
            self._wake.clear()
            if self._stop.is_set():
                return
            try:
                if self.restarts != self._restarts_handled:
                    self._restarts_handled = self.restarts
                    self._reinit()
                if self._recovery_asked:
                    self._recovery_asked = False
                    self._recover()
                self.poll()
            except Exception:  # the supervision must go on
                log.exception("gripper node %d: supervision failed", self.node.id)

    def _reinit(self) -> None:
        t0 = time.monotonic()
        try:
            self.configure()
            self._nmt_start()
            self.enable(self.reinit_timeout)
        except (GripperError, can.CanError, OSError) as e:
            msg = f"gripper node {self.node.id}: not enabled again after its restart: {e}"
            with self._lock:
                self._status.faults.append(msg)
            log.error("%s", msg)
            return
        log.warning("gripper node %d enabled again after its boot-up (configured and enabled in %.0f ms)",
                    self.node.id, (time.monotonic() - t0) * 1000)

    def device_faults(self) -> list[str]:
        """The faults the device itself reported (EMCY): a fault reset clears them, unlike
        a lost heartbeat or a gone bus, which end only when those come back."""
        with self._lock:
            return [f for f in self._status.faults if f.startswith("EMCY ")]

    def request_recovery(self) -> None:
        """Clears a device fault left by an earlier command, without waiting: CiA 402 fault
        reset, then shutdown, switch on, enable operation (on the wall clock in the
        supervision thread, under lockstep one step per frame in advance()). A fault that
        comes back stays in the status for the command to report."""
        self._recovery_asked = True
        self._wake.set()

    def _recover(self) -> None:  # wall clock, the supervision thread
        was = self.device_faults()
        try:
            self.fault_reset()
            self._wait_state(c.SWITCH_ON_DISABLED, self.reinit_timeout)
            self.enable(self.reinit_timeout)
        except GripperError as e:
            msg = f"gripper node {self.node.id}: not enabled again after a fault reset ({'; '.join(was)}): {e}"
            with self._lock:
                self._status.faults.append(msg)
            log.error("%s", msg)
            return
        log.warning("gripper node %d: fault reset (%s) and enabled again", self.node.id, "; ".join(was) or "no fault")

    def configure(self) -> None:
        """Configuration by SDO (start-up only; under lockstep, before the run)."""
        try:
            self.node.sdo[0x1017].raw = self.heartbeat_ms
            self.node.sdo[0x6060].raw = 1                     # profile position mode
            self.node.sdo[0x6081].raw = self.velocity
            self.node.sdo[0x6073].raw = self.force_limit
        except canopen.sdo.exceptions.SdoError as e:
            raise GripperError(f"gripper node {self.node.id}: configuration by SDO failed: {e}") from None

    # -- lockstep start-up and frames (never waits) ------------------------------------------
    def begin_startup(self, timeout_s: float = 5.0) -> None:
        """Lockstep: NMT start, then shutdown, switch on, enable operation, one step per
        frame once the device shows the state the last step asked for (advance())."""
        self.lockstep = True
        self._startup = [(c.CW_SHUTDOWN, c.READY_TO_SWITCH_ON), (c.CW_SWITCH_ON, c.SWITCHED_ON),
                         (c.CW_ENABLE_OPERATION, c.OPERATION_ENABLED)]
        self._startup_timeout = timeout_s
        self._startup_started = False

    @property
    def ready(self) -> bool:
        return self._startup is None and self._status.state == c.OPERATION_ENABLED

    def advance(self) -> None:
        """Lockstep, every frame: the next start-up step when due; heartbeat supervision."""
        now = self.clock()
        if self._last_heartbeat is None:
            self._last_heartbeat = now  # supervision starts with the run
        if self._recovery_asked and self._startup is None:
            self._recovery_asked = False  # lockstep recovery: the start-up's steps after a fault reset
            was = self.device_faults()
            self.fault_reset()
            log.warning("gripper node %d: fault reset (%s)", self.node.id, "; ".join(was) or "no fault")
            self._startup = [(c.CW_SHUTDOWN, c.READY_TO_SWITCH_ON), (c.CW_SWITCH_ON, c.SWITCHED_ON),
                             (c.CW_ENABLE_OPERATION, c.OPERATION_ENABLED)]
            self._startup_started, self._startup_deadline = True, now + self._startup_timeout
            self._send(c.CW_SHUTDOWN, self._status.position_um)
        if self._startup is not None:
            if not self._startup_started:
                self._nmt_start()
                self._startup_started, self._startup_deadline = True, now + self._startup_timeout
                self._send(self._startup[0][0], self._status.position_um)
            elif self._status.state == self._startup[0][1]:
                self._startup.pop(0)
                if self._startup:
                    self._send(self._startup[0][0], self._status.position_um)
                else:
                    self._startup = None
                    self._started = True
                    log.info("gripper node %d enabled", self.node.id)
            elif now > self._startup_deadline:
                msg = (f"start-up failed: state {self._status.state!r}, not {self._startup[0][1]!r}, "
                       f"after {self._startup_timeout:.1f} s")
                self._startup = None
                with self._lock:
                    self._status.faults.append(msg)
                log.error("gripper node %d: %s", self.node.id, msg)
        self.poll()

    def quiet_horizon(self) -> tuple[int, int] | None:
        """Lockstep: how far the next frames' advance() would change nothing, given no CAN
        frame (which comes with a frame that has work): (no frame limit, the sim time at
        which the heartbeat would count as lost), or None while the start-up or a
        recovery runs. The sim time is a millisecond early: the loss itself is judged on
        floating-point seconds by the frame that Python runs."""
        with self._lock:
            if self._startup is not None or self._recovery_asked or self._last_heartbeat is None:
                return None
            if self._hb_fault is not None:
                return (2**63 - 1, 2**63 - 1)  # lost already: only a heartbeat (a CAN frame) changes that
            lost_at = self._last_heartbeat + 3 * self.heartbeat_ms / 1000.0
        return (2**63 - 1, max(0, int(lost_at * 1e9) - 1_000_000))

    def snapshot(self, frame: int) -> None:
        """Lockstep: keep the status of this frame for the ticks of the next one."""
        self._snapshots[frame] = self._copy()
        for f in [f for f in self._snapshots if f < frame - 8]:
            del self._snapshots[f]

    def enable(self, timeout: float = 5.0) -> None:
        """The CiA 402 way to operation enabled: shutdown, switch on, enable operation
        (waits for each state; start-up or recovery only, never inside a tick)."""
        for cw, want in ((c.CW_SHUTDOWN, c.READY_TO_SWITCH_ON), (c.CW_SWITCH_ON, c.SWITCHED_ON),
                         (c.CW_ENABLE_OPERATION, c.OPERATION_ENABLED)):
            self._send(cw, self._status.position_um)
            self._wait_state(want, timeout)

    def _wait_state(self, want: str, timeout: float) -> None:
        try:
            wait_until(lambda: self.status().state == want, timeout, f"gripper node {self.node.id}: state {want!r}",
                       interval=0.005, diagnostic=lambda: f"its state is {self.status().state!r}")
        except WaitTimeout as e:
            raise GripperError(str(e).replace("\n", "; ")) from None

    # -- run time (non-blocking) -------------------------------------------------------------
    def _send(self, cw: int, target: int) -> None:
        rpdo = self.node.rpdo[1]
        rpdo["Controlword"].raw = cw
        rpdo["Target position"].raw = int(target)
        try:
            rpdo.transmit()
        except (can.CanError, OSError) as e:  # the bus is gone: say which, as a GripperError
            raise GripperError(f"gripper node {self.node.id}: {e}") from None
        self._cw = cw

    def command(self, width_um: int) -> None:
        """Moves the fingers to `width_um` (a close stops at an object, gripping it with the
        configured force limit). Sends two RPDOs: the new set-point bit low, then high.
        Statuses are `fresh` again once they can show the move: under lockstep from the
        tick four frames later (a tick of frame n: sent at n + 1, seen by the device at
        n + 2, its answer here at n + 3, shown to ticks of n + 4), on the wall clock after
        two more status updates."""
        tick = tick_context.current_tick() if self.lockstep else None
        with self._lock:
            self._fresh_after = (("frame", tick.frame + 4) if tick is not None
                                 else ("updates", self._status.updates + 2))
        self._send(c.CW_ENABLE_OPERATION, width_um)
        self._send(c.CW_ENABLE_OPERATION | c.CW_NEW_SET_POINT, width_um)

    def stop(self) -> None:
        self._send(c.CW_ENABLE_OPERATION | c.CW_HALT, self._status.position_um)

    def fault_reset(self) -> None:
        self._send(0, self._status.position_um)
        self._send(c.CW_FAULT_RESET, self._status.position_um)
        with self._lock:
            self._status.faults.clear()  # the device's; a lost heartbeat or bus stays until it is back

    def _time_label(self) -> str:
        """Now, for a fault's text: the wall clock's time of day, or under lockstep sim time."""
        if self.lockstep:
            return f"sim time {self.clock():.3f} s"
        t = time.time()
        return time.strftime("%H:%M:%S", time.localtime(t)) + f".{int(t * 1000) % 1000:03d}"

    def _bus_fault_now(self) -> str | None:
        """What is wrong with the bus itself, or None (the virtual bus's `fault`; a receive
        thread that died)."""
        bus = self.network.bus
        fault = getattr(getattr(bus, "real", bus), "fault", None)  # (under a LockstepCanLink: its bus)
        if fault:
            return fault
        exc = getattr(getattr(self.network, "notifier", None), "exception", None)
        return f"CAN receive failed: {exc}" if exc is not None else None

    def poll(self) -> None:
        """Supervision (the wall-clock thread calls it; under lockstep advance() does): the
        bus (wall clock only), then the heartbeat: none for 3 periods is the fault
        'gripper node N: heartbeat lost at <time>' until one comes again."""
        now = self.clock()
        bus_fault = None if self.lockstep else self._bus_fault_now()
        with self._lock:
            if bus_fault != self._bus_fault:
                self._bus_fault = bus_fault
                if bus_fault:
                    self._hb_fault = None  # the cause is named, not its consequence
                    log.error("gripper node %d: %s", self.node.id, bus_fault)
                else:
                    self._last_heartbeat = now  # its heartbeat can come again from now on
                    log.warning("gripper node %d: the CAN bus is back", self.node.id)
            if bus_fault or self._last_heartbeat is None:
                return
            silent = now - self._last_heartbeat
            lost = silent > 3 * self.heartbeat_ms / 1000.0
            if lost and self._hb_fault is None:
                self._hb_fault = (f"gripper node {self.node.id}: heartbeat lost at {self._time_label()} "
                                  f"(none for {silent * 1000:.0f} ms)")
                log.error("%s", self._hb_fault)
            elif not lost and self._hb_fault is not None:
                log.warning("gripper node %d: heartbeat back (%s)", self.node.id, self._hb_fault)
                self._hb_fault = None

    def _faults(self) -> list[str]:
        """The device's faults, then the bus's or the heartbeat's (last: the one a skill names)."""
        link = self._bus_fault or self._hb_fault
        return list(self._status.faults) + ([link] if link else [])

    def _copy(self) -> GripperStatus:
        with self._lock:
            s = self._status
            out = GripperStatus(s.state, s.statusword, s.position_um, s.grip, s.target_reached, self._faults(),
                                s.updates)
            kind, mark = self._fresh_after
            out.fresh = kind != "updates" or s.updates >= mark
            return out

    def status(self) -> GripperStatus:
        """The latest status; in a tick of frame n under lockstep, the status of frame n - 1."""
        tick = tick_context.current_tick() if self.lockstep else None
        if tick is None or not self._snapshots:
            return self._copy()
        older = [f for f in self._snapshots if f < tick.frame]
        frame = max(older) if older else min(self._snapshots)
        out = self._snapshots[frame]
        out = GripperStatus(out.state, out.statusword, out.position_um, out.grip, out.target_reached,
                            list(out.faults), out.updates)
        kind, mark = self._fresh_after
        out.fresh = kind != "frame" or tick.frame >= mark
        return out
