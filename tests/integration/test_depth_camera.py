"""The physics server's depth cameras between real processes: a lockstep participant asks
for captures and gets whole clouds back in the next frame, the same bit for bit on every
run; an unknown camera is refused naming the cameras there are; a camera with a rate
publishes on its own; `skillbus camera capture` asks a wall-clock server and writes PLY."""

from __future__ import annotations

import json
import sys

from conftest import last_json, TESTS
from skillbus import paths
from skillbus.sim import scene as scene_file

# 0.8 m over the demo table looking straight down (optical z = world -z): the table top
# fills the view (clear of the arm), with two cubes on it.
OVERHEAD = {"name": "overhead", "pose": [0.6, 0, 1.2, 1, 0, 0, 0], "width": 48, "height": 64, "fov_deg": 30}
EVERY_10_FRAMES = {"name": "slow", "pose": [0.5, 0, 1.2, 1, 0, 0, 0], "width": 8, "height": 6, "fov_deg": 20,
                   "rate_hz": 10}


def camera_scene(tmp_path, cameras):
    doc = json.loads(paths.demo_scene().read_text())
    doc["cameras"] = cameras
    return scene_file.save(doc, tmp_path / "camera.scene.json", paths.demo_scene())


def session(box, scene, tag, frames=40):
    sim = box.start(f"sim-{tag}", [str(paths.binary("sim_server")), "--scene", str(scene), "--participants", "eye",
                                   "--frames", str(frames)])
    eye = box.start(f"eye-{tag}", [sys.executable, str(TESTS / "integration" / "camera_participant.py"), "eye",
                                   "overhead,nope"])
    assert box.wait(sim, 120) == 0, sim.stderr()[-2000:]
    assert box.wait(eye, 30) == 0, eye.stderr()[-2000:]
    return last_json(sim.stdout()), last_json(eye.stdout())


def test_a_requested_capture_comes_back_whole_in_the_next_frame_and_the_same_every_run(sandbox, tmp_path):
    scene = camera_scene(tmp_path, [OVERHEAD, EVERY_10_FRAMES])
    runs = [session(sandbox, scene, str(i)) for i in range(2)]
    for sim, eye in runs:
        assert sim["ok"] and eye["ok"], (sim, eye)
        assert eye["bad_input"] == 0
        got = eye["answers"]["overhead"]
        assert got["cloud_frame"] == 2, "asked in frame 1, captured at the start of frame 2"
        assert (got["width"], got["height"]) == (48, 64)
        assert got["returns"] == 48 * 64, "the table fills the view"
        # In the world frame every return is on the table top (z 0.40) or on a cube (to 0.45).
        assert 0.3995 <= got["z_min"] and got["z_max"] <= 0.4505, got
        assert got["on_cube_tops"] > 10 and got["on_table"] > 2000, got
        # An unknown camera: refused, naming what there is.
        assert "no camera 'nope' in the scene (cameras: overhead, slow)" in eye["answers"]["nope"]["error"]
        # The camera with a rate: a capture every 10 frames (10 Hz of 10 ms frames), unasked.
        assert [r["frame"] for r in eye["rate"] if r["camera"] == "slow"] == [0, 10, 20, 30]
    (sim0, eye0), (sim1, eye1) = runs
    assert eye0["answers"]["overhead"]["sha256"] == eye1["answers"]["overhead"]["sha256"]
    assert sim0["session_digest"] == sim1["session_digest"]
    assert sim0["state_digest"] == sim1["state_digest"]


def test_skillbus_camera_capture_asks_a_wall_clock_server_and_writes_ply(sandbox, tmp_path):
    scene = camera_scene(tmp_path, [OVERHEAD])
    sim = sandbox.start("sim", [str(paths.binary("sim_server")), "--scene", str(scene), "--wall-clock"])
    sim.wait_for("wall-clock mode", 30)

    def cli(*args):
        p = sandbox.start(f"cli-{len(args)}-{args[0]}", [sys.executable, "-m", "skillbus.cli", "camera", "capture",
                                                         *args])
        return sandbox.wait(p, 30), p

    rc, p = cli("overhead", "--out", str(tmp_path / "cloud.ply"))
    assert rc == 0, p.stderr()
    s = last_json(p.stdout())
    assert s["returns"] == 48 * 64 and s["width"] == 48
    ply = (tmp_path / "cloud.ply").read_text().splitlines()
    assert f"element vertex {48 * 64}" in ply
    body = ply[ply.index("end_header") + 1:]
    zs = [float(line.split()[2]) for line in body]
    assert len(body) == 48 * 64 and all(0.3995 <= z <= 0.4505 for z in zs), sorted(zs)[:5] + sorted(zs)[-5:]
    rc, p = cli("nope", "--timeout", "10")
    assert rc == 1 and "no camera 'nope' in the scene (cameras: overhead)" in p.stderr()
    rc, p = cli("overhead", "--out", str(tmp_path / "cloud.txt"))
    assert rc == 2 and "write .ply or .npy" in p.stderr()
    sandbox.kill(sim, 15)
