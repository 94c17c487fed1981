"""The gripper driver: a CANopen master for one CiA 402 gripper, on the `canopen` package
(no hand-packed frames). Configuration by SDO at start-up only; at run time PDOs:
RPDO1 (controlword, target position) out, TPDO1 (statusword, position, grip state) in.

Non-blocking after start(): command() sends a set-point, status() returns the latest
state; nothing waits inside a skill's tick. poll() supervises the heartbeat (none for 3
periods: fault "device lost"); EMCY frames become faults with code and text; malformed
frames are counted and logged, never raised into a skill.

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

import canopen

from skillbus import tick_context
from skillbus.can import cia402 as c
from skillbus.can.eds import EDS
from skillbus.waiting import WaitTimeout, wait_until

log = logging.getLogger("gripper-driver")


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
                 velocity_um_s: int = 50_000, force_limit: int = 200, clock=time.monotonic) -> None:
        self.network, self.heartbeat_ms, self.clock = network, heartbeat_ms, clock
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
        self._cw = 0
        self.malformed = 0
        self.node.tpdo.read(from_od=True)
        self.node.tpdo[1].add_callback(self._on_tpdo)
        self.node.rpdo.read(from_od=True)
        self.node.nmt.add_heartbeat_callback(self._on_heartbeat)
        self.node.emcy.add_callback(self._on_emcy)
        network.subscribe(self.node.tpdo[1].cob_id, self._check_tpdo_length)

    # -- incoming ---------------------------------------------------------------------------
    def _check_tpdo_length(self, can_id, data, timestamp) -> None:
        if len(data) != 7:
            self.malformed += 1
            log.warning("TPDO1 of %d bytes (7 expected) ignored", len(data))

    def _on_tpdo(self, pdo) -> None:
        if len(pdo.data) != 7:
            return
        with self._lock:
            s = self._status
            s.statusword = pdo["Statusword"].raw
            s.state = c.state_of(s.statusword)
            s.position_um = pdo["Position actual value"].raw
            s.grip = pdo["Grip state"].raw
            s.target_reached = bool(s.statusword & c.SW_TARGET_REACHED)
            s.updates += 1

    def _on_heartbeat(self, state: int) -> None:
        self._last_heartbeat = self.clock()

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
        self.node.nmt.state = "OPERATIONAL"
        self.enable(timeout)

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
        if self._startup is not None:
            if not self._startup_started:
                self.node.nmt.state = "OPERATIONAL"
                self._startup_started, self._startup_deadline = True, now + self._startup_timeout
                self._send(self._startup[0][0], self._status.position_um)
            elif self._status.state == self._startup[0][1]:
                self._startup.pop(0)
                if self._startup:
                    self._send(self._startup[0][0], self._status.position_um)
                else:
                    self._startup = None
                    log.info("gripper node %d enabled", self.node.id)
            elif now > self._startup_deadline:
                msg = (f"start-up failed: state {self._status.state!r}, not {self._startup[0][1]!r}, "
                       f"after {self._startup_timeout:.1f} s")
                self._startup = None
                with self._lock:
                    self._status.faults.append(msg)
                log.error("gripper node %d: %s", self.node.id, msg)
        self.poll()

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
        rpdo.transmit()
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
            self._status.faults = [f for f in self._status.faults if f.startswith("device lost")]

    def poll(self) -> None:
        """Heartbeat supervision: no heartbeat for 3 periods is the fault 'device lost'."""
        if self._last_heartbeat is None:
            return
        silent = self.clock() - self._last_heartbeat
        if silent > 3 * self.heartbeat_ms / 1000.0:
            with self._lock:
                msg = f"device lost: no heartbeat from node {self.node.id} for {silent * 1000:.0f} ms"
                if not any(f.startswith("device lost") for f in self._status.faults):
                    self._status.faults.append(msg)
                    log.error("%s", msg)

    def _copy(self) -> GripperStatus:
        with self._lock:
            s = self._status
            out = GripperStatus(s.state, s.statusword, s.position_um, s.grip, s.target_reached, list(s.faults),
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
