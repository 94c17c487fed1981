"""The simulated gripper: one CANopen node (canopen's LocalNode) with the CiA 402 drive
profile and the EDS in deploy/can/skillbus_gripper.eds, speaking exactly the frames a
real CANopen gripper speaks. Standalone mode (here): an internal finger model stepped on
a timer. (Under lockstep it is to be driven by sim frames instead: not built yet.)

    skillbus gripper-device --channel gripper0 --node-id 5 [--object-width 40000]

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


class GripperDevice:
    def __init__(self, network: canopen.Network, node_id: int, eds: str | Path = EDS,
                 object_width: float | None = None) -> None:
        self.node = canopen.LocalNode(node_id, str(eds))
        network.add_node(self.node)
        self.model = FingerModel(object_width=object_width)
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
                self.model.target = self.model.width
                self.model.moving = False
            elif rising & c.CW_NEW_SET_POINT:
                self.model.target = max(0, min(MAX_WIDTH_UM, target))
                self.model.velocity = self.node.sdo[0x6081].raw or 1
                self.model.moving = True
                self.model.blocked_for = 0.0
                self.was_gripped = False

    def _fault(self, code: int) -> None:
        self.state, self.error_code = c.FAULT, code
        self.model.moving = False
        self.model.blocked_for = 0.0
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
        with self.lock:
            if self.state == c.OPERATION_ENABLED:
                self.model.step(dt)
                force = self.node.sdo[0x6073].raw
                if (self.model.moving and self.model.in_contact and force > RATED_FORCE
                        and self.model.blocked_for > BLOCKED_TIMEOUT_S):
                    self._fault(c.EMCY_OVER_CURRENT)
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
        if operational:
            tpdo.transmit()


def main(args) -> int:
    logging.basicConfig(level=logging.INFO)
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
