"""The gripper of a skill process: one GripperDriver, set up when the process starts
(``skillbus skills-process --gripper gripper0:5``) and used by the gripper skills.

Wall clock: the driver starts at once (waits for the device, configures it by SDO,
enables it), and its own thread then supervises the heartbeat and the bus and enables
a restarted device again. Lockstep: it is configured by SDO before the process joins the run, its CAN
traffic goes through a LockstepCanLink, and the start-up sequence and heartbeat
supervision advance with the process's frames, in sim time.
"""

from __future__ import annotations

import logging
from typing import Any

import can
import canopen

from skillbus.can.driver import GripperDriver, GripperError
from skillbus.waiting import WaitTimeout, wait_until

log = logging.getLogger("gripper-service")
_driver: GripperDriver | None = None
_link: Any = None


def parse(spec: str) -> tuple[str, int]:
    channel, _, node = spec.partition(":")
    if not channel:
        raise GripperError(f"--gripper {spec!r}: give CHANNEL[:NODE], e.g. gripper0:5")
    try:
        return channel, int(node) if node else 5
    except ValueError:
        raise GripperError(f"--gripper {spec!r}: the node id must be a number") from None


def setup(spec: str, interface: str = "skillbus_vcan", participant: Any = None, sdo_timeout: float = 10.0,
          **driver_args: Any) -> GripperDriver:
    global _driver, _link
    channel, node_id = parse(spec)
    network = canopen.Network()
    if participant is None:
        network.connect(interface=interface, channel=channel)
        _driver = GripperDriver(network, node_id, **driver_args)
        _driver.start(timeout=sdo_timeout)
        return _driver
    from skillbus.can.lockstep_link import LockstepCanLink, sdo_ids
    _link = LockstepCanLink(participant, can.Bus(interface=interface, channel=channel), channel, network,
                            sdo_ids(node_id))
    frame_ns = [0]

    def clock() -> float:
        # The sim time of the last frame whose on_frame ran or, acked by the quiet-frame
        # core, would have run (skillbus.quiet_frames): the same value either way.
        return max(frame_ns[0], participant.acked_sim_time_ns) * 1e-9

    _driver = GripperDriver(network, node_id, clock=clock, **driver_args)
    # By SDO, before the run (the device answers SDO outside the frames); the device may
    # still be starting, so try again until sdo_timeout.
    _driver.node.sdo.RESPONSE_TIMEOUT = 0.5
    try:
        wait_until(lambda: _driver.configure() or True, sdo_timeout, f"gripper node {node_id}: its configuration by SDO",
                   interval=0.0, retry_on=(GripperError,))
    except WaitTimeout as e:
        raise GripperError(f"{e.what}: not within {sdo_timeout:g} s: {e.__cause__}") from None
    _driver.begin_startup()
    inner, inner_horizon = participant.on_frame, participant.quiet_horizon

    def on_frame(frame: int, sim_time_ns: int) -> None:
        frame_ns[0] = sim_time_ns
        _driver.advance()
        _driver.snapshot(frame)  # (ticks read the newest snapshot before their frame: one at rest stays true)
        if inner is not None:
            inner(frame, sim_time_ns)

    def quiet_horizon() -> tuple[int, int] | None:
        """Frames with nothing for the link and the driver (and whatever ran before)."""
        mine = _driver.quiet_horizon() if _link.idle() else None
        if mine is None or inner is None:
            return mine
        theirs = inner_horizon() if inner_horizon is not None else None
        return None if theirs is None else (min(mine[0], theirs[0]), min(mine[1], theirs[1]))

    participant.on_frame = _link.wrap(on_frame)
    participant.quiet_horizon = quiet_horizon
    log.info("gripper on %s node %d (lockstep)", channel, node_id)
    return _driver


def interface(bus: Any, participant: Any, arg: str, can_interface: str = "skillbus_vcan", **options: Any) -> GripperDriver:
    """The gripper interface (skillbus.robot.interfaces): `arg` is CHANNEL[:NODE]."""
    return setup(arg, can_interface, participant, **options)


def driver() -> GripperDriver:
    """The process's gripper interface."""
    from skillbus.robot import interfaces
    try:
        return interfaces.get("gripper", hint="--gripper CHANNEL[:NODE]")
    except interfaces.InterfaceError as e:
        raise GripperError(str(e)) from None


def shutdown() -> None:
    global _driver, _link
    if _driver is not None:
        _driver.close()
    if _link is not None:
        _link.shutdown()
    elif _driver is not None:
        _driver.network.disconnect()
    _driver, _link = None, None
