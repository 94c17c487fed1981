"""Asks a wall-clock physics server's camera for one capture and prints what
skillbus.perception.segment finds in it, as JSON (tests/integration/test_perception.py)."""

from __future__ import annotations

import json
import sys

from skillbus.bus import open_bus
from skillbus.perception.depth_camera import DepthCamera
from skillbus.perception.segment import detect


def main() -> int:
    camera, noise = sys.argv[1], float(sys.argv[2]) if len(sys.argv) > 2 else 0.0
    cloud = DepthCamera(open_bus(), name="probe").capture(camera, timeout=20)
    scene = detect(cloud, noise_m=noise)
    print(json.dumps({"support_z": scene.support_z, "returns": cloud.returns,
                      "detections": [{"position": d.position, "yaw": d.yaw, "size": d.size, "points": d.points}
                                     for d in scene.detections]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
