"""The whole system clears the table: physics server, world model server, skill manager,
skill process, CANopen gripper device on the virtual CAN bus, motion service; every part
a real process, in lockstep. Run twice, and a third time under heavy CPU load from
another process: the same digests and the same final world model every time."""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import pytest

from clear_table_run import run_clear_table
from conftest import last_json, python_tool
from skillbus.demo import in_bin, scattered_scene
from skillbus.netns import Sandbox
from skillbus.system import programs, start


def clear_table(tmp: Path, name: str, load: bool = False, transport: str = "lcm", perception: bool = False,
                seed: int | None = None, task: str | None = None, physics_core: str = "off") -> dict:
    run = tmp / name
    run.mkdir(parents=True)
    with Sandbox(log_dir=run / "logs", transport=transport) as box:
        hog = None
        if load:  # another process keeps a core busy all along (and the other one now and then)
            hog = box.start("load", [sys.executable, "-c", "import time\nwhile True:\n    sum(range(10000))"])
        scene = scattered_scene(run / "scene", seed) if seed is not None else None
        out = run_clear_table(box, run, perception=perception, scene=scene, task=task, physics_core=physics_core)
        # the load ran for the whole session (it is never told to stop)
        out["load_ran_throughout"] = hog is not None and hog.returncode is None
    return out


def test_clear_table_on_dds_gives_the_same_digests_and_world_as_on_lcm(tmp_path):
    # Every part on Cyclone DDS instead of LCM: the same frames, physics, session digest,
    # every participant's digest and final world model (the transport is not the world).
    lcm, dds = clear_table(tmp_path, "lcm"), clear_table(tmp_path, "dds", transport="dds")
    assert dds["skill_mgr"]["tasks"] == {"1": "Success: all succeeded"}, dds["skill_mgr"]
    for key in ("frames", "state_digest", "session_digest"):
        assert dds["sim"][key] == lcm["sim"][key], key
    for n in ("wm", "skill_mgr", "skills", "gripper"):
        assert dds[n]["digest"] == lcm[n]["digest"], n
    assert dds["world_model"] == lcm["world_model"]


def test_clear_table_is_reproducible_bit_for_bit_even_under_load(tmp_path):
    # The second run places the physics server on a core of its own, as `skillbus demo`
    # does (skillbus.cpu_layout): timing only, the same digests.
    runs = [clear_table(tmp_path, "run0"), clear_table(tmp_path, "run1", physics_core="auto"),
            clear_table(tmp_path, "loaded", load=True)]
    first = runs[0]
    assert first["skill_mgr"]["tasks"] == {"1": "Success: all succeeded"}, first["skill_mgr"]
    # Every cube in the bin: in the physics server and in the world model.
    assert sorted(first["sim"]["objects"]) == ["blue", "green", "red"]
    for name, p in first["sim"]["objects"].items():
        assert in_bin(p), (name, p)
        assert first["world_model"][name]["in_type"] == "skiros:Bin", first["world_model"][name]
    # The post between the table and the bin stands in the straight way; the motion
    # service planned around it: the physics server saw the robot touch it in no step.
    assert first["sim"]["obstacle_contact_steps"] == {"post": 0}, first["sim"]
    # The Python participants set their start-up heap aside from the collector's walks
    # (skillbus.startup_heap): the skill process's libraries, ontology and replica.
    assert first["skills"]["startup_objects"] > 50_000, first["skills"]
    assert first["gripper"]["startup_objects"] > 10_000, first["gripper"]
    for r in runs[1:]:
        assert r["sim"]["frames"] == first["sim"]["frames"]
        assert r["sim"]["state_digest"] == first["sim"]["state_digest"]
        assert r["sim"]["session_digest"] == first["sim"]["session_digest"]
        for n in ("wm", "skill_mgr", "skills", "gripper"):
            assert r[n]["digest"] == first[n]["digest"], n
        assert r["world_model"] == first["world_model"]
    # the third run really shared the machine with the load from start to end
    assert runs[2]["load_ran_throughout"] and not runs[0]["load_ran_throughout"]


def test_a_skill_process_killed_during_pick_fails_the_task_and_is_restarted(transport_sandbox, tmp_path):
    """Under supervisord on the wall clock, as on a robot; on LCM and on DDS (where the
    restarted process once ran the killed one's last tick request, which its writer still
    held for late readers, and the task went on as if nothing had happened)."""
    sandbox = transport_sandbox
    run = tmp_path / "sup"
    run.mkdir()
    scenario = sandbox.start("scenario", python_tool("fault_scenario.py", str(run)))
    assert sandbox.wait(scenario, 420) == 0, scenario.stdout()[-3000:] + scenario.stderr()[-3000:]
    r = json.loads(scenario.stdout().strip().splitlines()[-1])
    assert r["registered"] and r["pick_seen"]
    assert r["first_exit"] != 0
    # Named: the manager's tick times out, or reaches the restarted process (which has lost
    # the instance), or the process's new announcement tells the manager it restarted.
    assert re.search(r"task 1: Failure: .*skill process skills (did not answer the tick of|was restarted while running"
                     r"|has no running instance)", r["first_output"]), r["first_output"]
    assert r["failed_after_s"] < 10
    assert r["restarted"] and r["registered_again"], r
    assert r["second_exit"] == 0, r["second_output"]
    assert r["physics_in_bin"] == {"red": True, "green": True, "blue": True}, r
    assert r["world_model_bin"] == ["skiros:Cube-2", "skiros:Cube-3", "skiros:Cube-4"], r
    # supervisord kept every process's output in one folder
    logs = run / "logs"
    assert {"sim.err", "wm.err", "skills.err", "skill_mgr.err", "gripper.err", "supervisord.log"} <= \
        {p.name for p in logs.iterdir()}


def test_locate_adds_the_objects_the_world_model_does_not_know(tmp_path):
    """The world model starts without the blue cube; Locate (the simulated camera) adds
    it, contained in the table, at the pose the physics server reports."""
    from skillbus import paths
    from skillbus.sim import scene as scene_file
    run = tmp_path / "locate"
    run.mkdir()
    scene = run / "demo.scene.json"
    scene_file.save(json.loads(paths.demo_scene().read_text()), scene, paths.demo_scene())
    belief = scene_file.load(scene)
    belief["objects"] = [o for o in belief["objects"] if o["name"] != "blue"]
    (run / "demo.ttl").write_text(scene_file.to_turtle(belief))
    with Sandbox(log_dir=run / "logs") as box:
        procs = start(box, programs(run, scene=scene, task="Locate Location=skiros:Table-1"), run)
        assert box.wait(procs["sim"], 300) == 0, procs["sim"].stderr()[-2000:]
        assert box.wait(procs["skill_mgr"], 60) == 0
        task = last_json(procs["skill_mgr"].stdout())["tasks"]["1"]
        sim = last_json(procs["sim"].stdout())
        where = box.start("where", python_tool("wm_where.py", str(run)))
        assert box.wait(where, 60) == 0, where.stderr()[-2000:]
        wm = json.loads(where.stdout().strip().splitlines()[-1])
    assert task == "Success: located 3 object(s); new: blue", task
    assert wm["blue"]["in"] == "table" and wm["blue"]["in_type"] == "skiros:Table"
    assert wm["blue"]["pose"] == pytest.approx(sim["objects"]["blue"], abs=1e-3)


def test_with_perception_the_cubes_are_located_by_the_camera_and_placed_side_by_side(tmp_path):
    # Locate finds the cubes in the overhead depth camera's cloud (1 mm of noise), Pick
    # grasps them at the perceived poses, Place puts each at a free spot of the bin from the
    # occupancy map: all in the bin, none within 3 cm of another, the same digests twice.
    runs = [clear_table(tmp_path, f"perceived{i}", perception=True) for i in range(2)]
    first = runs[0]
    assert first["skill_mgr"]["tasks"] == {"1": "Success: all succeeded"}, first["skill_mgr"]
    cubes = first["sim"]["objects"]
    assert sorted(cubes) == ["blue", "green", "red"]
    for name, p in cubes.items():
        assert in_bin(p), (name, p)
        assert first["world_model"][name]["in_type"] == "skiros:Bin", first["world_model"][name]
    names = sorted(cubes)
    gaps = [math.dist(cubes[a][:3], cubes[b][:3]) for i, a in enumerate(names) for b in names[i + 1:]]
    assert min(gaps) > 0.03, gaps
    assert all(abs(p[2] - 0.045) < 0.003 for p in cubes.values()), cubes  # side by side on the floor, none stacked
    assert first["map"]["clouds"] >= 2 and first["map"]["bad_input"] == 0, first["map"]
    assert first["sim"]["obstacle_contact_steps"] == {"post": 0}, first["sim"]
    # The Python participants set their start-up heap aside from the collector's walks
    # (skillbus.startup_heap): the skill process's libraries, ontology and replica.
    assert first["skills"]["startup_objects"] > 50_000, first["skills"]
    assert first["gripper"]["startup_objects"] > 10_000, first["gripper"]
    second = runs[1]
    for key in ("frames", "state_digest", "session_digest"):
        assert second["sim"][key] == first["sim"][key], key
    assert second["map"]["map_digest"] == first["map"]["map_digest"]


@pytest.mark.parametrize("seed", [1])  # make demo's; seeds 2-5 were run by hand (docs/pick_and_place.md)
def test_cubes_at_seeded_random_places_are_cleared_around_the_post(tmp_path, seed):
    # `make demo`: the cubes at random places of the table from a seed (1 by default), the
    # camera and the map, the post in the way: every cube in the bin, side by side, and the
    # arm never touched the post.
    r = clear_table(tmp_path, f"seed{seed}", perception=True, seed=seed)
    assert r["skill_mgr"]["tasks"] == {"1": "Success: all succeeded"}, r["skill_mgr"]
    cubes = r["sim"]["objects"]
    assert sorted(cubes) == ["blue", "green", "red"]
    for name, p in cubes.items():
        assert in_bin(p), (name, p)
        assert r["world_model"][name]["in_type"] == "skiros:Bin", r["world_model"][name]
    names = sorted(cubes)
    assert min(math.dist(cubes[a][:3], cubes[b][:3]) for i, a in enumerate(names) for b in names[i + 1:]) > 0.03
    assert r["sim"]["obstacle_contact_steps"] == {"post": 0}, r["sim"]


TWO_IN_THE_BIN = 'TaskPlan Goal="(skiros:contain skiros:Bin-5 skiros:Cube-2), (skiros:contain skiros:Bin-5 skiros:Cube-4)"'


def test_task_plan_puts_two_cubes_in_the_bin_the_same_way_every_run(tmp_path):
    # Goals, not a tree: TaskPlan plans Pick and Place for the red and the blue cube from the
    # skills' conditions and the world model (Fast Downward), and runs them under lockstep.
    runs = [clear_table(tmp_path, f"plan{i}", task=TWO_IN_THE_BIN) for i in range(2)]
    first = runs[0]
    assert first["skill_mgr"]["tasks"] == {"1": "Success: all succeeded"}, first["skill_mgr"]
    wm = first["world_model"]
    assert wm["red"]["in_type"] == "skiros:Bin" and wm["blue"]["in_type"] == "skiros:Bin", wm
    assert wm["green"]["in_type"] == "skiros:Table", wm  # no goal of its own: it stays
    assert in_bin(first["sim"]["objects"]["red"]) and in_bin(first["sim"]["objects"]["blue"])
    assert not in_bin(first["sim"]["objects"]["green"])
    for key in ("frames", "state_digest", "session_digest"):
        assert runs[1]["sim"][key] == first["sim"][key], key
    for n in ("wm", "skill_mgr", "skills", "gripper"):
        assert runs[1][n]["digest"] == first[n]["digest"], n
