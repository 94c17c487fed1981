"""The robot interface is not the simulator: with no physics server at all, a stand-in for
a real robot's drivers (robot_driver_standin.py: the robot's channels only, on the wall
clock) serves the standard skills. Locate writes what its camera sees into the world
model; MoveArm plans with the motion service, sends the trajectory, and succeeds when the
driver reports it played; a trajectory the driver refuses fails MoveArm with the driver's
reason. Nobody publishes on a simulator channel."""

from __future__ import annotations

import json
import math
import re
import signal
import sys

from conftest import last_json, python_tool
from skillbus import paths
from test_skills import cli, mgr_binary

# What the stand-in's camera sees: red 2 cm off where the scene has it, and a cube the
# world model does not know.
SEEN = [["red", 0.42, 0.17, 0.425], ["green", 0.5, -0.1, 0.425], ["blue", 0.6, 0.05, 0.425],
        ["yellow", 0.45, -0.25, 0.425]]


def tree(sandbox) -> dict:
    """Every element of the world model's containment tree by label: (id, container id,
    position relative to the container)."""
    rc, out, err = cli(sandbox, "wm", "tree", "--json")
    assert rc == 0, err
    found: dict = {}

    def walk(n, parent):
        found[n["label"]] = (n["id"], parent, n["position"])
        for c in n["children"]:
            walk(c, n["id"])

    for root in json.loads(out):
        walk(root, None)
    return found


def test_a_real_driver_stand_in_serves_locate_and_move_arm_without_a_physics_server(sandbox, tmp_path):
    scene = paths.demo_scene()
    sandbox.start("wm", [str(paths.binary("wm_server")), "--wall-clock", "--data", str(tmp_path / "wm"),
                         "--scene", str(scene.with_suffix("").with_suffix(".ttl"))])
    sandbox.start("motion", [str(paths.binary("motion_server")), "--scene", str(scene)])
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    # joint1 within 1 rad: the table is reachable (about 0.4 rad), the bin (1.57 rad) is not.
    driver = sandbox.start("driver", python_tool("robot_driver_standin.py", "--objects", json.dumps(SEEN),
                                                 "--joint1-limit", "1.0"))
    driver.wait_for('"driver": "ready"', 30, stream="stdout")
    skills = sandbox.start("skills", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "skills",
                                      "--world-model", "--arm", "--interface", "camera=skillbus.robot.camera",
                                      "--library", "skillbus.skills.manipulation"])
    skills.wait_for("registered", 60)
    before = tree(sandbox)

    rc, out, err = cli(sandbox, "run", "Locate", "-p", "Location=skiros:Table-1", "--timeout", "60")
    assert rc == 0, out + err
    assert "located 4 object(s); new: yellow" in out, out
    after = tree(sandbox)
    red_id, table, red_at = after["red"]
    assert table == before["table"][0] == after["yellow"][1], "yellow is added on the table, red stays there"
    moved = [a - b for a, b in zip(red_at, before["red"][2])]
    assert math.dist(moved, [0.02, 0.02, 0.0]) < 1e-6, moved  # the camera's pose, relative to the table
    assert math.dist(after["green"][2], before["green"][2]) < 1e-6

    rc, out, err = cli(sandbox, "run", "MoveArm", "-p", "Arm=skiros:Arm-8", "-p", f"Target={red_id}",
                       "--timeout", "60")
    assert rc == 0, out + err
    assert f"at 10.0 cm above {red_id}" in out, out

    rc, out, err = cli(sandbox, "run", "MoveArm", "-p", "Arm=skiros:Arm-8", "-p", "Target=skiros:Bin-5",
                       "-p", "Height=0.45", "--timeout", "60")
    assert rc == 1, out + err
    # (the move goes around the demo's post: its first waypoint turns joint1 past 1 rad already)
    assert re.search(r"the robot rejected the trajectory: joint1 target 1\.\d+ at point \d+ is outside \+-1\.0 rad", out), out

    sandbox.kill(driver, signal.SIGTERM)
    assert sandbox.wait(driver, 15) == 0, driver.stderr()[-2000:]
    summary = last_json(driver.stdout())
    commands = summary["commands"]
    assert [c["accepted"] for c in commands] == [True, False], commands
    assert all(c["id"].startswith("move_arm@") and c["joints"] == [f"joint{i}" for i in range(1, 7)]
               for c in commands), commands
    assert summary["sim_messages"] == {}, "something talked to a simulator"
    assert summary["sim_modules"] == [] and summary["frames"] > 50
