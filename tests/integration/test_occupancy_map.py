"""The occupancy map between real processes: one capture of the demo scene by a camera
over the table, and the table top and the cubes are occupied, the space over them free,
what is under the table top unknown (at named points); save, clear and load give the map
back; under lockstep the map and a participant's answers are the same on every run."""

from __future__ import annotations

import json
import sys
import time

from conftest import last_json, TESTS
from skillbus import paths
from skillbus.sim import scene as scene_file

# 0.9 m over the demo table looking down (optical z = world -z): the table, its three
# cubes and some floor beyond it.
# The demo scene's camera, over the table and the post, without its noise.
OVERHEAD = {"name": "overhead", "pose": [0.32, 0.18, 1.6, 1, 0, 0, 0], "width": 400, "height": 300, "fov_deg": 54}
# (x, y, top z) of the demo's cubes, spots of the table top with no cube, and the post's top.
CUBES = {"red": (0.4, 0.15, 0.45), "green": (0.5, -0.1, 0.45), "blue": (0.6, 0.05, 0.45)}
TABLE = [(0.3, -0.25, 0.40), (0.7, 0.25, 0.40), (0.6, -0.3, 0.40)]
POST = [(0.3, 0.5, 0.60), (0.27, 0.47, 0.60)]


def named_points():
    """Per surface: just under and just over it (the surface's voxel is one of the two, as
    the surface lies on a voxel boundary), well over it (free) and under it (unknown)."""
    pts = []
    for x, y, z in [*CUBES.values(), *TABLE, *POST]:
        pts += [(x, y, z - 0.004), (x, y, z + 0.004), (x, y, z + 0.15), (x, y, z - 0.03)]
    return pts


def check_named(states):
    for i, (x, y, z) in enumerate([*CUBES.values(), *TABLE, *POST]):
        under, over, above, inside = states[4 * i:4 * i + 4]
        assert "occupied" in (under, over), ((x, y, z), under, over)  # the surface
        assert above == "free", ((x, y, z), above)                      # the space over it
        assert inside == "unknown", ((x, y, z), inside)                 # never seen: under the top


def camera_scene(tmp_path):
    doc = json.loads(paths.demo_scene().read_text())
    doc["cameras"] = [OVERHEAD]
    return scene_file.save(doc, tmp_path / "camera.scene.json", paths.demo_scene())


def cli(box, *args, timeout=30):
    p = box.start(f"cli-{time.monotonic_ns()}", [sys.executable, "-m", "skillbus.cli", *args])
    rc = box.wait(p, timeout)
    return rc, (json.loads(p.stdout().splitlines()[-1]) if rc == 0 else p.stderr())


def mapped_overhead(sandbox, tmp_path, maps):
    """A wall-clock physics server with the overhead camera and a map server (its maps in
    `maps`) that has taken one capture: the map server's process and its info."""
    sandbox.start("sim", [str(paths.binary("sim_server")), "--scene", str(camera_scene(tmp_path)), "--wall-clock"])
    mapper = sandbox.start("map", [str(paths.binary("map_server")), "--maps", str(maps)])
    mapper.wait_for("serving", 30)
    assert cli(sandbox, "camera", "capture", "overhead")[0] == 0
    deadline = time.monotonic() + 15
    while (info := cli(sandbox, "map", "info")[1])["clouds"] < 1:
        assert time.monotonic() < deadline, info
        time.sleep(0.2)
    return mapper, info


def test_one_capture_maps_the_table_and_cubes_and_the_map_saves_and_loads(sandbox, tmp_path):
    maps = tmp_path / "maps"
    maps.mkdir()
    mapper, info = mapped_overhead(sandbox, tmp_path, maps)
    assert info["captures"] == {"overhead": 0} and info["resolution"] == 0.01
    flat = [str(v) for p in named_points() for v in p]
    rc, got = cli(sandbox, "map", "state", *flat)
    assert rc == 0, got
    states = [g["state"] for g in got]
    check_named(states)
    # Regions: a slab over an empty part of the table is free; over a cube it is not.
    rc, empty = cli(sandbox, "map", "free-area", "0.62", "-0.35", "0.415", "0.78", "-0.15", "0.44")
    assert rc == 0 and empty["free_m2"] >= 0.9 * empty["area_m2"] > 0, empty
    rc, cube = cli(sandbox, "map", "free-area", "0.35", "0.1", "0.415", "0.45", "0.2", "0.44")
    assert rc == 0 and cube["free_m2"] <= cube["area_m2"] - 0.002, cube  # the red cube's 5 x 5 cm are not free
    rc, counts = cli(sandbox, "map", "box", "0.2", "-0.4", "0.39", "0.8", "0.4", "0.41")
    assert rc == 0 and counts["occupied"] > 1000, counts
    # Saved, cleared, loaded: the same answers.
    rc, saved = cli(sandbox, "map", "save", "demo")
    assert rc == 0 and saved["file"] == str(maps / "demo.bt") and (maps / "demo.bt").stat().st_size > 100
    assert cli(sandbox, "map", "clear")[1]["clouds"] == 0
    assert {g["state"] for g in cli(sandbox, "map", "state", *flat)[1]} == {"unknown"}
    assert cli(sandbox, "map", "load", "demo")[0] == 0
    assert [g["state"] for g in cli(sandbox, "map", "state", *flat)[1]] == states
    # Off the happy path: a path for a name, a missing map, wrong arguments.
    rc, err = cli(sandbox, "map", "load", "../demo")
    assert rc == 1 and "a name, not a path" in err
    rc, err = cli(sandbox, "map", "load", "none")
    assert rc == 1 and "cannot read a binary OctoMap (.bt) from" in err
    assert cli(sandbox, "map", "state", "1", "2")[0] == 2
    assert cli(sandbox, "map", "box", "1", "2", "3")[0] == 2
    rc, err = cli(sandbox, "map", "box", "0", "0", "0", "10", "10", "10")
    assert rc == 1 and "at most 20000000 are looked at" in err
    sandbox.kill(mapper, 15)
    assert sandbox.wait(mapper, 15) == 0
    assert last_json(mapper.stdout())["bad_input"] == 0


def lockstep_run(box, scene, tag):
    sim = box.start(f"sim-{tag}", [str(paths.binary("sim_server")), "--scene", str(scene), "--participants",
                                   "eye,map", "--frames", "12", "--ack-timeout-ms-of", "map=60000"])
    mapper = box.start(f"map-{tag}", [str(paths.binary("map_server")), "--lockstep", "map", "--exit-with-session"])
    eye = box.start(f"eye-{tag}", [sys.executable, str(TESTS / "integration" / "map_participant.py"), "eye",
                                   json.dumps(named_points())])
    for p in (sim, mapper, eye):
        assert box.wait(p, 120) == 0, p.stderr()[-2000:]
    return last_json(sim.stdout()), last_json(mapper.stdout()), last_json(eye.stdout())


def test_under_lockstep_the_map_and_its_answers_are_the_same_every_run(sandbox, tmp_path):
    scene = camera_scene(tmp_path)
    runs = [lockstep_run(sandbox, scene, str(i)) for i in range(2)]
    for sim, mapper, eye in runs:
        assert sim["ok"] and mapper["ok"] and eye["ok"], (sim, mapper, eye)
        assert mapper["clouds"] == 1 and mapper["bad_input"] == 0
        # Asked in frame 5: the map as of frame 5, holding the capture of frame 2.
        assert eye["info"]["frame"] == 5 and eye["info"]["captures"] == {"overhead": 0}
        check_named(eye["states"])
    assert runs[0][1]["map_digest"] == runs[1][1]["map_digest"]
    assert runs[0][2]["states"] == runs[1][2]["states"]
    assert runs[0][0]["session_digest"] == runs[1][0]["session_digest"]
