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
    # The newest state of each frame heard since the last one taken, by its frame (handlers
    # run in canonical order): catch_up steps with that of the last frame the core acked.
    by_frame: dict[int, bytes] = {}

    def on_state(m) -> None:
        raw[0] = by_frame[m.stamp.frame] = m.data
        while len(by_frame) > 4:
            del by_frame[min(by_frame)]

    def take_state() -> None:
        # Decoded only while the fingers move or were just told to: at rest nothing in
        # the state can change what the device reports (it is the only one moving them).
        if raw[0] is None or at_rest():
            return
        s = decode_sim_state(raw[0])
        raw[0] = None
        by_frame.clear()
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

    holding = [False]  # the frames the core acks are held ones (finger_watch), not at rest

    def catch_up(frame: int, sim_time_ns: int) -> None:
        """Frames acked within the horizon: what their steps would have done, before this
        frame's CAN frames (an RPDO's TPDO restarts the event timer). At rest they only
        counted towards the timer; holding an object each stepped the fingers with its
        state, the last of which is the acked frame's (the watch kept them all within its
        bounds)."""
        done, done_ns = p.previous_frame
        if last_frame[0] is not None and done > last_frame[0]:
            n = done - last_frame[0]
            if holding[0]:
                dt = ((done_ns - last[0]) // n) * 1e-9  # (each frame's (t - t_before) * 1e-9: one period)
                data = by_frame.get(done)
                s = decode_sim_state(data) if data is not None else None
                if data is not None and s is None:
                    bad[0] += 1  # (as that frame would have counted it)
                if s is not None and take_sim_state(dev, fingers, s, state_ch):
                    last_state[0] = s
                for _ in range(n):
                    dev.step(dt)
            else:
                dev.frames_passed(n)
            last[0], last_frame[0] = done_ns, done
        holding[0] = False

    def on_frame(frame: int, sim_time_ns: int) -> None:
        if last[0] is None:
            dev.boot()  # boot-up in the first frame: nothing but SDO goes out before the run
        dt = (sim_time_ns - last[0]) * 1e-9 if last[0] is not None else 0.0
        last[0], last_frame[0] = sim_time_ns, frame
        take_state()
        dev.step(dt)
        dev.heartbeat_if_due(sim_time_ns)

    def quiet_horizon() -> tuple | None:
        # (holding[0] stays as it is until catch_up: whatever the core acks until the next
        # frame in Python is acked in one mode, since only such a frame changes the fingers)
        if last_frame[0] is None or not link.idle():
            return None
        if at_rest():
            return dev.quiet_horizon(last_frame[0])
        # Holding an object: quiet while the physics keeps the fingers as they are now.
        watch = dev.finger_watch() if last_state[0] is not None and raw[0] is None else None
        horizon = dev.quiet_horizon(last_frame[0]) if watch is not None else None
        if horizon is None:
            return None
        holding[0] = True
        return (*horizon, {state_ch: watch})

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
