"""A lockstep participant that asks the depth cameras for captures (tests/integration/
test_depth_camera.py): at frame 1 one capture of each camera named on the command line,
then it reads the answers until the session ends and prints a JSON summary (per request: the error, or the
cloud's size, returns and SHA-256 of its points) and every cloud seen at a camera's rate."""

from __future__ import annotations

import hashlib
import json
import sys

from skillbus.bus import open_bus
from skillbus.lockstep import LockstepParticipant
from skillbus.perception.depth_camera import CameraError, DepthCamera


def heights(z) -> dict:
    """Where the returns are in height (world z): the lowest, the highest, how many on a
    5 cm cube's top (0.45) and on the demo table's top (0.40)."""
    return {"z_min": float(z.min()), "z_max": float(z.max()), "on_cube_tops": int(((z > 0.449) & (z < 0.451)).sum()),
            "on_table": int(((z > 0.399) & (z < 0.401)).sum())}


def main() -> int:
    name, cameras = sys.argv[1], sys.argv[2].split(",")
    bus = open_bus()
    p = LockstepParticipant(bus, name)
    cam = DepthCamera(bus, p, name=name)
    asked: dict[str, str] = {}
    out: dict = {"answers": {}, "rate": []}
    seen_rate: set[tuple[str, int]] = set()

    def on_frame(frame: int, t: int) -> None:
        if frame == 1:
            for c in cameras:
                asked[c] = cam.request(c)
        for c in cameras:
            rid = asked.get(c)
            if rid is None or c in out["answers"]:
                continue
            try:
                cloud = cam.answer(rid)
            except CameraError as e:
                out["answers"][c] = {"error": str(e), "frame": frame}
                continue
            if cloud is not None:
                out["answers"][c] = {"frame": frame, "cloud_frame": cloud.frame, "width": cloud.width,
                                     "height": cloud.height, "returns": cloud.returns, "pose": list(cloud.pose),
                                     "sha256": hashlib.sha256(cloud.points.tobytes()).hexdigest(),
                                     **heights(cloud.world_points()[:, 2])}
        for c, cloud in cam.latest.items():
            if not cloud.request_id and (c, cloud.capture) not in seen_rate:
                seen_rate.add((c, cloud.capture))
                out["rate"].append({"camera": c, "capture": cloud.capture, "frame": cloud.frame})

    p.on_frame = on_frame
    r = p.run()
    out.update(ok=r.ok, error=r.error, frames=r.frames, digest=r.digest_hex, bad_input=sum(cam.bad_input.by_channel.values()))
    print(json.dumps(out), flush=True)
    return 0 if r.ok else 1


if __name__ == "__main__":
    sys.exit(main())
