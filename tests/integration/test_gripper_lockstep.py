"""The gripper in lockstep with the physics server: the Grasp skill in a skill process
drives the CANopen driver over the virtual SocketCAN bus; the simulated device is a
lockstep participant whose fingers are the physics server's; the world model learns that
the gripper holds the cube. Every part is a real process."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

from conftest import last_json
from skillbus import paths
from skillbus.netns import Sandbox
from skillbus.sim import scene as scene_file
from skillbus.sim.arm_poses import ARM, top_down
from skillbus.sim.scripts import CUBE
from skillbus.waiting import wait_until
from test_skills import mgr_binary

FRAMES = 400  # 4 s of sim time
PARTICIPANTS = "wm,skill_mgr,grip_skills,gripper"


def grasp_scene(tmp: Path, object_width_ok: bool = True) -> tuple[Path, Path]:
    """The demo scene with the open fingers already around the green cube (or, without
    the cube, around nothing)."""
    s = json.loads(paths.demo_scene().read_text())
    s["robot"]["initial_joints"].update(dict(zip(ARM, top_down(CUBE[0], CUBE[1], CUBE[2] + 0.005))))
    if not object_width_ok:
        s["objects"] = [o for o in s["objects"] if o["name"] != "green"]
    f = tmp / "grasp.scene.json"
    scene_file.save(s, f, paths.demo_scene())
    ttl = tmp / "grasp.ttl"
    ttl.write_text(scene_file.to_turtle(scene_file.load(f)))
    return f, ttl


def session(box: Sandbox, tmp: Path, start: str, with_cube: bool = True, device_env: dict | None = None) -> dict:
    scene, ttl = grasp_scene(tmp, with_cube)
    sock = tmp / "grip.sock"
    box.start("can-hub", [sys.executable, "-m", "skillbus.cli", "can-hub", "--channel", str(sock)])
    wait_until(sock.exists, 10, f"the CAN hub's socket {sock}", interval=0.02)
    sim = box.start("sim", [str(paths.binary("sim_server")), "--scene", str(scene), "--participants", PARTICIPANTS,
                            "--frames", str(FRAMES), "--join-timeout-ms", "30000"])
    device = box.start("gripper", [sys.executable, "-m", "skillbus.cli", "gripper-device", "--channel", str(sock),
                                   "--node-id", "5", "--lockstep", "--name", "gripper"], env=device_env)
    wm = box.start("wm", [paths.binary("wm_server"), "--data", str(tmp / "wm"),
                          "--scene", str(ttl)])
    mgr = box.start("skill_mgr", [str(mgr_binary()), "--start", start])
    skills = box.start("grip_skills", [sys.executable, "-m", "skillbus.cli", "skills-process", "--lockstep",
                                       "--name", "grip_skills", "--library", "skillbus.skills.gripper",
                                       "--world-model", "--gripper", f"{sock}:5"])
    assert box.wait(sim, 120) == 0, sim.stderr()[-3000:] + skills.stderr()[-3000:] + device.stderr()[-2000:]
    out = {"sim": last_json(sim.stdout())}
    for name, p in (("mgr", mgr), ("skills", skills), ("device", device), ("wm", wm)):
        box.wait(p, 30)
        out[name] = last_json(p.stdout())
    out["wm_log"] = wm.stderr()
    return out


def test_grasp_closes_the_fingers_on_the_cube_and_the_world_model_knows(tmp_path):
    # The second run's device takes every frame in Python (SKILLBUS_NATIVE=0); the first's
    # frames at rest and holding the cube are acked by the quiet-frame core: the digests
    # must not tell them apart.
    runs = []
    for i, env in enumerate((None, {"SKILLBUS_NATIVE": "0"})):
        with Sandbox(log_dir=tmp_path / f"run{i}" / "logs") as box:
            runs.append(session(box, tmp_path / f"run{i}", "Grasp Gripper=skiros:Gripper-7 Object=skiros:Cube-3",
                                device_env=env))
    assert runs[0]["device"]["quiet_frames"] > 0 and runs[1]["device"]["quiet_frames"] == 0
    # Holding the cube (most of the session) its frames are acked by the core too, while the
    # physics keeps the fingers stalled on it (the finger watch): 6 of 400 without it.
    assert runs[0]["device"]["quiet_frames"] > FRAMES // 2, runs[0]["device"]
    for r in runs:
        assert r["sim"]["ok"], r["sim"]["error"]
        task = r["mgr"]["tasks"]["1"]
        assert task.startswith("Success: grasp: skiros:Gripper-7 holds skiros:Cube-3 at 5"), task
        assert r["device"]["ok"] and r["device"]["can_sent"] > 0 and r["device"]["can_received"] > 0
        assert r["device"]["rpdo_errors"] == 0
        assert r["sim"]["commands_accepted"] >= 1  # the device's set-point reached the physics
        # closed on the 5 cm cube, squeezing with the configured 20 N (0x6073 = 200), not more
        assert abs(r["sim"]["finger_width"] - 0.05) < 0.002
        assert 18.0 <= r["sim"]["finger_force"] <= 20.0 + 1e-6
    # Bit for bit the same: the physics, every lockstep message, the manager's run.
    assert runs[0]["sim"]["state_digest"] == runs[1]["sim"]["state_digest"]
    assert runs[0]["sim"]["session_digest"] == runs[1]["sim"]["session_digest"]
    assert runs[0]["mgr"]["digest"] == runs[1]["mgr"]["digest"]
    assert runs[0]["device"]["digest"] == runs[1]["device"]["digest"]


def test_grasp_on_nothing_fails_with_the_width_named(tmp_path):
    # Without the green cube the scene's ids shift: name the gripper that this world has
    # (the manager refuses an id that is not in the world model).
    _, ttl = grasp_scene(tmp_path, object_width_ok=False)
    gripper = re.search(r"skiros:Gripper-\d+", ttl.read_text()).group(0)
    with Sandbox(log_dir=tmp_path / "logs") as box:
        r = session(box, tmp_path, f"Grasp Gripper={gripper} Object=skiros:Cube-2", with_cube=False)
    task = r["mgr"]["tasks"]["1"]
    assert re.match(r"Failure: grasp: nothing gripped \(the fingers closed to 0\.\d mm\)", task), task
