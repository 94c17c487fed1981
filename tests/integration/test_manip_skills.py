"""The manipulation-command skill family against the real system (issue "Manipulation-
command skills"): the DART physics server on the cabinet scene, under lockstep, with the
world model, the skill manager, the motion service, the CANopen gripper and a skill
process serving skillbus.manip.library. Each skill is started with `skillbus run` and its
effect is read from the physics (the ground truth on SB_SIM_STATE, the articulated
joints on SB_ROBOT_ARTICULATION) and from the world model."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import pytest

from conftest import last_json
from skillbus import paths
from skillbus.waiting import wait_until

SCENE = paths.REPO_ROOT / "deploy" / "scenes" / "cabinet.scene.json"
TASK = paths.REPO_ROOT / "deploy" / "tasks" / "drawer_pick_place.yaml"
PROBE = Path(__file__).parent / "manip_probe.py"


@pytest.fixture
def cabinet(sandbox, tmp_path):
    """The system on the cabinet scene, no task started; the element ids by label."""
    from skillbus.sim.scene import element_ids
    from skillbus.system import programs, start
    run = tmp_path / "run"
    run.mkdir()
    procs = start(sandbox, programs(run, scene=SCENE, task=None, manip=True), run)
    procs["skills"].wait_for("registered", 60)
    ids = element_ids(SCENE)
    return {"sandbox": sandbox, "ids": ids, "base": ["-p", f"Arm={ids['arm']}", "-p", f"Gripper={ids['gripper']}"]}


def cli(sandbox, *args: str, timeout: float = 180) -> tuple[int, str, str]:
    p = sandbox.start(f"cli-{args[0]}-{len(sandbox.procs)}", [sys.executable, "-m", "skillbus.cli", *map(str, args)])
    rc = sandbox.wait(p, timeout)
    return rc, p.stdout(), p.stderr()


def run_skill(sys_, skill: str, *params: str, expect: int = 0) -> str:
    rc, out, err = cli(sys_["sandbox"], "run", skill, *sys_["base"], *params, "--timeout", "150")
    assert rc == expect, f"{skill}: exit {rc}\n{out[-3000:]}\n{err[-2000:]}"
    return out


def physics(sys_) -> dict:
    p = sys_["sandbox"].start(f"probe-{len(sys_['sandbox'].procs)}", [sys.executable, str(PROBE)])
    assert sys_["sandbox"].wait(p, 40) == 0, p.stdout() + p.stderr()
    return last_json(p.stdout())


def wm_element(sys_, eid: str) -> dict:
    rc, out, err = cli(sys_["sandbox"], "wm", "get", eid, "--json", timeout=30)
    assert rc == 0, out + err
    return json.loads(out)


def tilt_deg(q) -> float:
    x, y, z, w = q
    zz = 1 - 2 * (x * x + y * y)  # the z component of the body's z axis
    return math.degrees(math.acos(max(-1.0, min(1.0, zz))))


def test_open_close_and_rotate_move_the_drawer_and_the_door(cabinet):
    ids = cabinet["ids"]
    drawer, door = ids["cabinet/drawer_joint"], ids["cabinet/door_joint"]
    before = physics(cabinet)["joints"]
    assert before["cabinet/drawer_joint"]["position"] == pytest.approx(0, abs=0.005)

    run_skill(cabinet, "ManipOpen", "-p", f"Object={drawer}", "-p", "distance=0.15")
    j = physics(cabinet)["joints"]
    assert j["cabinet/drawer_joint"]["position"] >= 0.12, j  # open by at least 12 cm
    assert wm_element(cabinet, drawer)["properties"]["skiros:JointPosition"][0] >= 0.12

    run_skill(cabinet, "ManipClose", "-p", f"Object={drawer}")
    assert physics(cabinet)["joints"]["cabinet/drawer_joint"]["position"] <= 0.03

    run_skill(cabinet, "ManipOpen", "-p", f"Object={door}", "-p", "angle=0.7")
    a = physics(cabinet)["joints"]["cabinet/door_joint"]["position"]
    assert a >= 0.56, a  # the door opened by at least 32 degrees

    run_skill(cabinet, "ManipRotate", "-p", f"Object={door}", "-p", "angle=-0.3")
    b = physics(cabinet)["joints"]["cabinet/door_joint"]["position"]
    assert a - b >= 0.24, (a, b)

    run_skill(cabinet, "ManipClose", "-p", f"Object={door}")
    assert physics(cabinet)["joints"]["cabinet/door_joint"]["position"] <= 0.15
    # rotate refuses a prismatic joint, naming it
    out = run_skill(cabinet, "ManipRotate", "-p", f"Object={drawer}", expect=1)
    assert "is prismatic, not revolute" in out


def test_the_drawer_task_from_yaml_puts_the_cube_in_the_closed_drawer(cabinet):
    ids = cabinet["ids"]
    out = run_skill(cabinet, "ManipTask", "-p", f"Task={TASK}")
    assert "ManipClose" in out, out[-2000:]
    s = physics(cabinet)
    assert s["joints"]["cabinet/drawer_joint"]["position"] <= 0.03
    cube = s["objects"]["red"]
    handle = s["joints"]["cabinet/drawer_joint"]["handle"]
    # inside the closed drawer: on its floor (0.255 m), behind its handle by half the drawer
    # (the drawer's axis is the world's y)
    assert cube[2] == pytest.approx(0.28, abs=0.01), (cube, handle)
    assert math.dist(cube[:2], [handle[0], handle[1] - 0.13]) < 0.06, (cube, handle)
    red = wm_element(cabinet, ids["red"])
    assert red["relations"] == [[ids["cabinet/drawer_joint"], "skiros:contain", ids["red"]]], red
    assert wm_element(cabinet, ids["cabinet/drawer_joint"])["properties"]["skiros:JointPosition"][0] < 0.03


def test_pick_variants_and_place(cabinet):
    ids = cabinet["ids"]
    red, green, table = ids["red"], ids["green"], ids["table"]
    z0 = physics(cabinet)["objects"]["red"][2]
    run_skill(cabinet, "ManipPick", "-p", f"Object={red}")
    assert physics(cabinet)["objects"]["red"][2] > z0 + 0.06
    run_skill(cabinet, "ManipPlace", "-p", f"Object={red}", "-p", f"Location={table}", "-p",
              "Config=offset: [-0.05, 0.15]\nrelease_height: 0.46")
    s = physics(cabinet)["objects"]["red"]
    assert s[2] < z0 + 0.01 and math.dist(s[:2], [0.45, 0.15]) < 0.03, s

    out = run_skill(cabinet, "ManipFailpick", "-p", f"Object={green}", expect=1)
    assert "failpick: a labelled failure" in out, out[-2000:]
    g0 = physics(cabinet)["objects"]["green"]
    assert g0[2] < 0.44  # still on the table

    run_skill(cabinet, "ManipManualpick", "-p", f"Object={green}", "-p",
              "Config=grasp_pose: [0, 0, 0.005, 0, 0.7071068, 0.7071068, 0]")
    assert physics(cabinet)["objects"]["green"][2] > g0[2] + 0.06
    run_skill(cabinet, "ManipPlace", "-p", f"Object={green}", "-p", f"Location={table}", "-p",
              "Config=offset: [0.05, -0.1]\nrelease_height: 0.46")
    out = run_skill(cabinet, "ManipDynamicpick", "-p", f"Object={green}")
    assert physics(cabinet)["objects"]["green"][2] > 0.48
    run_skill(cabinet, "ManipPlace", "-p", f"Object={green}", "-p", f"Location={table}", "-p",
              "Config=offset: [0.05, -0.1]\nrelease_height: 0.46")

    run_skill(cabinet, "ManipFlip", "-p", f"Object={red}")
    assert tilt_deg(physics(cabinet)["objects"]["red"][3:]) > 60


def test_motion_skills_reach_what_they_say(cabinet):
    ids = cabinet["ids"]
    t0 = physics(cabinet)["tool"]
    run_skill(cabinet, "ManipMove", "-p", "Config=offset: [0.0, 0.0, 0.06]")
    t1 = physics(cabinet)["tool"]
    assert t1[2] - t0[2] == pytest.approx(0.06, abs=0.005) and math.dist(t1[:2], t0[:2]) < 0.005
    run_skill(cabinet, "ManipTrack", "-p", "Config=waypoints: [[0.05, 0, 0], [0.05, 0.05, 0], [0, 0.05, 0]]")
    t2 = physics(cabinet)["tool"]
    assert math.dist(t2[:3], [t1[0], t1[1] + 0.05, t1[2]]) < 0.005
    run_skill(cabinet, "ManipGotoPose", "-p", "Config=pose: [0.45, 0.0, 0.6, 0, 0, 1, 0]")
    assert math.dist(physics(cabinet)["tool"][:3], [0.45, 0.0, 0.6]) < 0.005
    run_skill(cabinet, "ManipApproachRotate", "-p", f"Object={ids['green']}")
    s = physics(cabinet)
    green, tool = s["objects"]["green"], s["tool"]
    assert math.dist(tool[:3], [green[0], green[1], green[2] + 0.12]) < 0.005, (tool, green)
    out = run_skill(cabinet, "ManipScan", "-p", f"Object={ids['green']}")
    assert "4 command(s) done" in out, out
    tool = physics(cabinet)["tool"]  # the last of 4 viewpoints: 6 cm to the -y side, 15 cm up
    assert math.dist(tool[:3], [green[0], green[1] - 0.06, green[2] + 0.15]) < 0.005, (tool, green)
    run_skill(cabinet, "ManipGripperAction", "-p", "gripper_state=-1")
    assert physics(cabinet)["finger_width"] < 0.005
    run_skill(cabinet, "ManipGripperAction", "-p", "gripper_state=1")
    assert physics(cabinet)["finger_width"] > 0.07
    out = run_skill(cabinet, "ManipJointCtrl", "-p", "Config=joints: {joint1: 0.3, joint9: 1}", expect=1)
    assert "unknown joint(s) joint9" in out, out
    run_skill(cabinet, "ManipJointCtrl", "-p", "Config=joints: {joint1: 0.3}")
    t3 = physics(cabinet)["tool"]
    assert math.atan2(t3[1], t3[0]) == pytest.approx(0.3, abs=0.02)  # the arm turned to joint1 = 0.3 rad
    run_skill(cabinet, "ManipWait", "-p", "frames=20")
    assert math.dist(physics(cabinet)["tool"][:3], t3[:3]) < 0.002


@pytest.fixture
def cabinet_real_time(sandbox, tmp_path):
    """The cabinet system on the wall clock: the physics at real time."""
    from skillbus.sim.scene import element_ids
    from skillbus.system import programs, start
    run = tmp_path / "run"
    run.mkdir()
    procs = start(sandbox, programs(run, scene=SCENE, task=None, manip=True, lockstep=False), run)
    procs["skills"].wait_for("registered", 60)
    ids = element_ids(SCENE)
    return {"sandbox": sandbox, "ids": ids, "base": ["-p", f"Arm={ids['arm']}", "-p", f"Gripper={ids['gripper']}"]}


def test_a_manipulation_skill_stopped_mid_drag_holds_the_arm(cabinet_real_time):
    """Ctrl-C to `skillbus run` stops the task (SkiROS2's preemption): the skill says at
    which command it stopped, and the arm holds where it is. On the wall clock: a lockstep
    session runs the drag at 10-15x real time, faster than the test can look (each look a
    process of its own) and stop it, so whether it stopped mid-drag was a race."""
    import signal
    import time
    cabinet = cabinet_real_time
    box, ids = cabinet["sandbox"], cabinet["ids"]
    p = box.start("run-open", [sys.executable, "-m", "skillbus.cli", "run", "ManipOpen", *cabinet["base"], "-p",
                               f"Object={ids['cabinet/drawer_joint']}", "-p", "distance=0.15", "-p", "speed=0.1",
                               "--timeout", "150"])
    # (at a third of its default speed: each look is a process that takes a second to start on
    # a loaded machine, and the drag must still be under way when the stop lands)
    wait_until(lambda: physics(cabinet)["joints"]["cabinet/drawer_joint"]["position"] >= 0.03, 60,
               "the drawer 3 cm open", interval=0.05)
    p.popen.send_signal(signal.SIGINT)
    assert box.wait(p, 30) == 130, p.stdout() + p.stderr()
    out = p.stdout() + p.stderr()
    assert "preempted: open at command" in out, out
    a = physics(cabinet)
    time.sleep(1.0)
    b = physics(cabinet)
    assert b["frame"] > a["frame"] + 10  # the session went on
    assert math.dist(a["tool"][:3], b["tool"][:3]) < 0.003, (a["tool"], b["tool"])  # the arm holds
    drawer = b["joints"]["cabinet/drawer_joint"]["position"]
    assert 0.03 <= drawer < 0.14, drawer  # stopped part of the way
