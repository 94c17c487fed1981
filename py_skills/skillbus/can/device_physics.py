"""The simulated gripper on the wall clock with the physics server's fingers
(``skillbus gripper-device --physics``; the physics server in wall-clock mode): CAN
through canopen's notifier, frames from a local timer."""

from __future__ import annotations

import json
import signal

import canopen

from skillbus import startup_heap
from skillbus.can.device import EDS, GripperDevice, step_on_the_wall_clock, summary, take_sim_state
from skillbus.can.fingers import SimFingers


def run(args) -> int:
    """The device on the wall clock with the physics server's fingers (the physics server
    in wall-clock mode): CAN through canopen's notifier, frames from a local timer."""
    from skillbus.bus import open_bus
    from skillbus.lockstep import LockstepParticipant
    from skillbus.sim.state_decode import decode_sim_state
    from skillbus.sim.messages import gripper_channel, state_channel

    bus = open_bus(args.url)
    p = LockstepParticipant(bus, args.name, kind="gripper-device", wall_clock=True,
                            wall_frame_period_ns=int(args.period_ms * 1e6))
    network = canopen.Network()
    network.connect(interface=args.interface, channel=args.channel)
    fingers = SimFingers(lambda m: bus.publish(gripper_channel(), m.encode()))
    dev = GripperDevice(network, args.node_id, args.eds or EDS, fingers=fingers)
    bad = [0]  # states that did not decode (values that are not sane: dev.rejects)

    def on_state(m) -> None:
        s = decode_sim_state(m.data)
        if s is None:
            bad[0] += 1
            return
        take_sim_state(dev, fingers, s, m.channel)

    p.subscribe(state_channel(), on_state)
    dev.boot()
    print(json.dumps({"node": args.node_id, "channel": args.channel, "physics": True}), flush=True)
    p.on_frame = lambda frame, t: step_on_the_wall_clock(dev, args.period_ms / 1000.0)
    interrupted = []

    def on_sigint(signum, frame) -> None:  # Ctrl-C ends the run; the summary below is printed
        interrupted.append(signum)
        p.stop()

    signal.signal(signal.SIGINT, on_sigint)
    failure: OSError | None = None
    startup_heap.set_aside()
    try:
        p.run()
    except OSError as e:
        failure = e  # LCM's wait cut short by the signal raises OSError, before on_sigint has run
    finally:
        network.disconnect()
        print(json.dumps(summary(dev, bad[0] + p.bad_input.total, node=args.node_id, channel=args.channel)),
              flush=True)
    if failure is not None and not interrupted:  # (by now on_sigint has run, if it was the signal)
        raise failure
    return 0
