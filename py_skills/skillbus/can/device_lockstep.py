"""The simulated gripper as a lockstep participant (``skillbus gripper-device --lockstep``):
its fingers are the physics server's (SimFingers); CAN goes through the lockstep link,
and everything the device sends (TPDO, heartbeat, EMCY) is driven by sim frames."""

from __future__ import annotations

import json

import canopen

from skillbus import startup_heap
from skillbus.can.device import EDS, GripperDevice, summary, take_sim_state
from skillbus.can.fingers import SimFingers


def run(args) -> int:
    """The device as a lockstep participant, its fingers those of the physics server."""
    import can

    from skillbus.bus import open_bus
    from skillbus.can.lockstep_link import LockstepCanLink, sdo_ids
    from skillbus.lockstep import LockstepParticipant
    from skillbus.sim.state_decode import decode_sim_state
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
        if raw[0] is None or at_rest():
            return
        s = decode_sim_state(raw[0])
        raw[0] = None
        if s is None:
            bad[0] += 1
            return
        if take_sim_state(dev, fingers, s, state_ch):
            last_state[0] = s

    state_ch = state_channel()
    # Only the newest state is read (take_state): frames at rest whose only message is
    # the state are acked without the interpreter (quiet_horizon below).
    p.subscribe(state_ch, on_state, latest_only=True)
    last: list[int | None] = [None]
    last_frame: list[int | None] = [None]
    last_state: list = [None]

    def at_rest() -> bool:
        return not (fingers.moving or not fingers.acknowledged or last_state[0] is None)

    def catch_up(frame: int, sim_time_ns: int) -> None:
        """Frames acked within the horizon, at rest: what their steps would have done, before
        this frame's CAN frames (an RPDO's TPDO restarts the event timer)."""
        before, before_ns = p.previous_frame
        if last_frame[0] is not None and before > last_frame[0]:
            dev.frames_passed(before - last_frame[0])
            last[0], last_frame[0] = before_ns, before

    def on_frame(frame: int, sim_time_ns: int) -> None:
        if last[0] is None:
            dev.boot()  # boot-up in the first frame: nothing but SDO goes out before the run
        dt = (sim_time_ns - last[0]) * 1e-9 if last[0] is not None else 0.0
        last[0], last_frame[0] = sim_time_ns, frame
        take_state()
        dev.step(dt)
        dev.heartbeat_if_due(sim_time_ns)

    def quiet_horizon() -> tuple[int, int] | None:
        if last_frame[0] is None or not at_rest() or not link.idle():
            return None
        return dev.quiet_horizon(last_frame[0])

    framed = link.wrap(on_frame)

    def frame_of_device(frame: int, sim_time_ns: int) -> None:
        catch_up(frame, sim_time_ns)
        framed(frame, sim_time_ns)

    p.on_frame = frame_of_device
    p.quiet_horizon = quiet_horizon
    print(json.dumps({"node": args.node_id, "channel": args.channel, "lockstep": args.name}), flush=True)
    set_aside = startup_heap.set_aside()
    r = p.run()
    p.close()
    link.shutdown()
    print(json.dumps(summary(dev, bad[0] + link.rejects.total + p.bad_input.total, ok=r.ok, error=r.error,
                             frames=r.frames, quiet_frames=p.quiet_frames, digest=r.digest_hex, can_sent=link.stats["sent"],
                             can_received=link.stats["received"], can_rejected=link.rejects.summary(),
                             startup_objects=set_aside)), flush=True)
    return 0 if r.ok else 1
