"""A lockstep participant that asks the overhead camera for one capture (frame 1) and, in
frame 5, asks the occupancy map about points given as JSON on the command line (as of its
frame 5: the same answer every run); prints a JSON summary (tests/integration/
test_occupancy_map.py)."""

from __future__ import annotations

import json
import sys

from skillbus.bus import open_bus
from skillbus.lockstep import LockstepParticipant
from skillbus.perception.depth_camera import DepthCamera
from skillbus.perception.map_client import MapClient


def main() -> int:
    name, points = sys.argv[1], json.loads(sys.argv[2])
    bus = open_bus()
    p = LockstepParticipant(bus, name)
    cam = DepthCamera(bus, p, name=name)
    world = MapClient(bus, p, name=name, timeout=20.0)
    out: dict = {}

    def on_frame(frame: int, t: int) -> None:
        if frame == 1:
            out["request"] = cam.request("overhead")
        if frame == 5:
            out["info"] = world.info()
            out["states"] = world.states(points)

    p.on_frame = on_frame
    r = p.run()
    out.update(ok=r.ok, error=r.error, frames=r.frames, digest=r.digest_hex)
    print(json.dumps(out), flush=True)
    return 0 if r.ok else 1


if __name__ == "__main__":
    sys.exit(main())
