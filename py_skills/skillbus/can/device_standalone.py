"""The simulated gripper standalone (``skillbus gripper-device``): its own finger model
(FingerModel, an object of --object-width between the fingers) stepped on a wall-clock
timer every --period-ms; for tests of the driver without the physics server. While the
bus is gone (the virtual bus's hub restarting) it goes on stepping and sends nothing,
as a device whose cable is cut."""

from __future__ import annotations

import json
import time

import canopen

from skillbus import startup_heap
from skillbus.can.device import EDS, GripperDevice, step_on_the_wall_clock, summary


def run(args) -> int:
    network = canopen.Network()
    network.connect(interface=args.interface, channel=args.channel)
    dev = GripperDevice(network, args.node_id, args.eds or EDS, args.object_width)
    dev.boot()
    print(json.dumps({"node": args.node_id, "channel": args.channel}), flush=True)
    period = args.period_ms / 1000.0
    next_t = time.monotonic()
    startup_heap.set_aside()
    try:
        while True:  # standalone: the finger model on a wall-clock timer
            next_t += period
            step_on_the_wall_clock(dev, period)
            time.sleep(max(0.0, next_t - time.monotonic()))
    except KeyboardInterrupt:
        pass
    finally:
        network.disconnect()
        print(json.dumps(summary(dev, node=args.node_id, channel=args.channel)), flush=True)
    return 0
