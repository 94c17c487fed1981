"""The physics server as a real process: DART stepping under lockstep with a scripted
participant over LCM, in a private network namespace."""

from __future__ import annotations

import json
import math
import re
import sys
import sysconfig
import time
from pathlib import Path

import pytest

from conftest import last_json
from support.skip_policy import cannot_run
from skillbus.sim.scripts import CUBE, HOME, ARM, arm, gripper, grasp_and_carry, grasp_lift_release, sweep
from skillbus import paths
from skillbus.sim import scene as scene_file
from skillbus.sim.session import run_script_session


def at(record, t):
    """The recorded state nearest to sim time t."""
    return min(record["states"], key=lambda s: abs(s["t"] - t))


def test_grasp_lift_and_release_twice_gives_bitwise_the_same_digest(sandbox, tmp_path):
    runs = [run_script_session(sandbox, grasp_lift_release(), 10.0, tmp_path / f"run{i}", timeout=120)
            for i in range(2)]
    for r in runs:
        assert r["sim"]["ok"], r["sim"]["error"]
        assert r["script"]["ok"], r["script"]["error"]
        assert r["sim"]["frames"] == 1000 and r["sim"]["commands_accepted"] == 5
    # Determinism: every position and velocity after 10 s, bit for bit, and every message.
    assert runs[0]["sim"]["state_digest"] == runs[1]["sim"]["state_digest"]
    assert runs[0]["sim"]["session_digest"] == runs[1]["sim"]["session_digest"]
    assert runs[0]["script"]["digest"] == runs[1]["script"]["digest"]
    # The physics does not see how commands arrive: the same script played in-process
    # (no participant) ends in the same state.
    script_file = tmp_path / "run0" / "script.json"
    alone = sandbox.start("alone", [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()),
                                    "--script", str(script_file), "--duration-s", "10"])
    assert sandbox.wait(alone, 120) == 0
    assert last_json(alone.stdout())["state_digest"] == runs[0]["sim"]["state_digest"]

    rec = runs[0]["record"]
    z0 = CUBE[2]
    closed = at(rec, 4.9)
    assert 0.048 < closed["finger_width"] < 0.052, "the fingers stop on the 5 cm cube"
    assert closed["finger_force"] == pytest.approx(20.0, abs=0.5), "squeezing with the force limit"
    assert {c["finger"] for c in closed["contacts"] if c["object"] == "green"} == {"finger_left", "finger_right"}
    # Lifted 10 cm: the cube's height follows the tool's within 5 mm all the way up and while held.
    before_tool, before_cube = closed["tool_pose"][2], closed["objects"]["green"]["pose"][2]
    for s in rec["states"]:
        if 5.0 <= s["t"] <= 7.5:
            rise_tool = s["tool_pose"][2] - before_tool
            rise_cube = s["objects"]["green"]["pose"][2] - before_cube
            assert abs(rise_cube - rise_tool) < 0.005, s["t"]
    held = at(rec, 7.4)
    assert held["objects"]["green"]["pose"][2] - z0 == pytest.approx(0.10, abs=0.005)
    # Opened: it falls back onto the table (and stays upright there).
    end = rec["last_state"]
    assert end["finger_width"] > 0.07
    assert end["objects"]["green"]["pose"][2] == pytest.approx(z0, abs=0.002)
    assert not end["contacts"]
    # The other cubes never moved.
    for name in ("red", "blue"):
        assert math.dist(end["objects"][name]["pose"][:3], rec["states"][0]["objects"][name]["pose"][:3]) < 1e-3


def test_a_joint_trajectory_is_tracked_within_0_01_rad(sandbox, tmp_path):
    script = sweep()
    r = run_script_session(sandbox, script, 4.0, tmp_path)
    assert r["sim"]["ok"] and r["script"]["ok"], (r["sim"], r["script"])
    rec = r["record"]
    moving = [s for s in rec["states"] if 0.5 < s["t"] <= 3.5]
    assert max(s["arm_tracking_error"] for s in moving) < 0.01
    # At each waypoint's time, every joint is where the waypoint says (the server's own
    # error figure is not trusted alone).
    start = 0.51  # the command goes out in the frame at 0.5 s and is applied at its end
    for t, q in script["steps"][0]["arm"]["points"]:
        s = at(rec, start + t)
        for name, want in zip(ARM, q):
            assert s["joints"][name] == pytest.approx(want, abs=0.01), (t, name)
    end = rec["last_state"]
    for name, want in zip(ARM, script["steps"][0]["arm"]["points"][-1][1]):
        assert end["joints"][name] == pytest.approx(want, abs=1e-3)
        assert abs(end["velocities"][name]) < 1e-3


def test_bad_commands_are_rejected_and_the_robot_holds_its_position(sandbox, tmp_path):
    nan = float("nan")
    script = {"record_every": 10, "steps": [
        arm(0.1, "nan", [[1.0, [0.0, nan, 1.6, 0.0, 1.3, 0.0]]]),
        arm(0.2, "limit", [[1.0, [0.0, 3.0, 1.6, 0.0, 1.3, 0.0]]]),
        arm(0.3, "unknown", [[1.0, [0.5]]], joints=["joint9"]),
        arm(0.4, "finger", [[1.0, [0.01]]], joints=["finger_left_joint"]),
        arm(0.5, "too-fast", [[0.1, [2.0, 0.2, 1.6, 0.0, 1.3416, 0.0]]]),
        arm(0.6, "count", [[1.0, [0.1, 0.2]]]),
        gripper(0.7, "wide", 0.5),
        gripper(0.8, "force", 0.02, force=-1),
        gripper(0.9, "speed", 0.02, speed=nan),
        {"at_s": 1.0, "wrong_type": "arm"},
        {"at_s": 1.0, "raw": {"channel": "gripper", "hex": "deadbeef"}},
        gripper(1.5, "ok", 0.0),
    ]}
    r = run_script_session(sandbox, script, 3.0, tmp_path)
    assert r["sim"]["ok"], r["sim"]["error"]  # still running to the end
    replies = {x["id"]: x for x in r["record"]["replies"]}
    expected = {
        "nan": "not a finite number",
        "limit": "joint2 target 3 at point 0 is outside its limits",
        "unknown": "unknown arm joint 'joint9' (the arm has joint1, joint2",
        "finger": "unknown arm joint 'finger_left_joint'",
        "too-fast": "joint1 would move at 20 rad/s",
        "count": "point 0 has 2 positions for 6 joints",
        "wide": "width 0.500000 m is outside [0, 0.080000]",
        "force": "force_limit -1.000000 N is outside",
        "speed": "must be finite numbers",
    }
    for cmd_id, text in expected.items():
        assert not replies[cmd_id]["accepted"], cmd_id
        assert text in replies[cmd_id]["error"], (cmd_id, replies[cmd_id]["error"])
    assert replies["ok"]["accepted"]
    assert r["sim"]["commands_rejected"] == len(expected) + 1  # + the message of the wrong type
    assert r["sim"]["bad_input"] >= 2  # the wrong type and the unstamped bytes
    end = r["record"]["last_state"]
    for name, want in zip(ARM, HOME):
        assert end["joints"][name] == pytest.approx(want, abs=2e-3), name
    assert end["finger_width"] < 0.002  # the one good command was carried out


def test_rejections_are_logged(sandbox, tmp_path):
    script = {"steps": [arm(0.1, "bad", [[1.0, [9.0]]], joints=["joint1"])]}
    run_script_session(sandbox, script, 0.5, tmp_path)
    sim = next(p for p in sandbox.procs if p.name == "sim")
    assert re.search(r"rejected arm command 'bad': joint1 target 9", sim.stderr())


def test_a_script_longer_than_its_session_fails_naming_the_steps_not_played(sandbox, tmp_path):
    # Before, the steps after the session's end were left out with exit 0 ("steps_left"
    # in its summary only).
    script = {"steps": [gripper(0.1, "early", 0.02), gripper(2.0, "late", 0.0), gripper(3.0, "later", 0.0)]}
    r = run_script_session(sandbox, script, 0.5, tmp_path)
    assert r["sim"]["ok"] and not r["script"]["ok"] and r["script"]["steps_left"] == 2, r
    assert r["script"]["error"].startswith("2 step(s) not played"), r["script"]
    part = next(p for p in sandbox.procs if p.name == "script")
    assert part.popen.returncode == 1, part.stderr()[-2000:]
    assert "error: sim-script: 2 step(s) not played: the session ended at sim time 0.490 s, before the step " \
           "at 2.0 s" in part.stderr(), part.stderr()[-2000:]
    # The same script played in-process by the physics server, on either clock.
    script_file = tmp_path / "script.json"
    for clock in ([], ["--wall-clock", "--speed", "10", "--frames", "25"]):
        alone = sandbox.start(f"alone{len(clock)}", [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()),
                                                     "--script", str(script_file), "--duration-s", "0.5", *clock]
                              if not clock else [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()),
                                                 "--script", str(script_file), *clock])
        assert sandbox.wait(alone, 60) == 1, alone.stderr()[-2000:]
        summary = last_json(alone.stdout())
        assert not summary["ok"] and f"2 step(s) of {script_file} not played: the session ended at sim time " \
                                     in summary["error"] and "before the step at 2 s" in summary["error"], summary


def test_a_slow_participant_makes_the_master_wait_without_skipping_frames(sandbox, binary):
    sim = sandbox.start("sim", [str(binary("sim_server")), "--scene", str(paths.demo_scene()),
                                "--participants", "slow,fast", "--frames", "100"])
    slow = sandbox.start("slow", [sys.executable, "-m", "skillbus.cli", "lockstep-participant", "--name", "slow",
                                  "--slow-at-frame", "50"])
    fast = sandbox.start("fast", [str(binary("sb_demo_participant")), "--name", "fast"])
    assert sandbox.wait(sim, 60) == 0, sim.stderr()[-2000:]
    s = last_json(sim.stdout())
    assert s["ok"] and s["frames"] == 100
    assert s["wall_time_s"] > 0.8  # it waited out the slow frame (0.8 s) instead of running on
    for p in (slow, fast):
        assert sandbox.wait(p, 15) == 0
        assert last_json(p.stdout())["frames"] == 100  # every frame, none skipped


def test_a_dead_participant_stops_the_server_with_an_error_naming_it(sandbox, binary):
    sim = sandbox.start("sim", [str(binary("sim_server")), "--scene", str(paths.demo_scene()),
                                "--participants", "alive,doomed", "--ack-timeout-ms", "1500"])
    alive = sandbox.start("alive", [str(binary("sb_demo_participant")), "--name", "alive"])
    doomed = sandbox.start("doomed", [sys.executable, "-m", "skillbus.cli", "lockstep-participant", "--name",
                                      "doomed", "--bare"])
    sim.wait_for("starting frames", 30)
    time.sleep(0.5)
    sandbox.kill(doomed)
    assert sandbox.wait(sim, 30) == 1
    s = last_json(sim.stdout())
    assert not s["ok"] and s["frames"] > 0
    assert re.search(r"no ack for frame \d+ from participant\(s\) doomed", s["error"]), s["error"]
    sandbox.wait(alive, 15)


def test_a_bad_scene_file_is_refused_with_the_field_named(sandbox, binary, tmp_path):
    bad = json.loads(paths.demo_scene().read_text())
    bad["objects"][1]["mass"] = 0
    f = tmp_path / "bad.scene.json"
    scene_file.save(bad, f, paths.demo_scene())
    sim = sandbox.start("sim", [str(binary("sim_server")), "--scene", str(f), "--frames", "1"])
    assert sandbox.wait(sim, 30) == 2
    assert f"{f}: objects[1].mass must be > 0" in sim.stderr()
    missing = sandbox.start("sim2", [str(binary("sim_server")), "--scene", str(tmp_path / "none.json")])
    assert sandbox.wait(missing, 30) == 2
    assert "cannot open the scene file" in missing.stderr()


def sim_cli(box, *args):
    """`skillbus sim ...` inside the sandbox: (exit code, JSON reply or error text)."""
    p = box.start(f"cli-{time.monotonic_ns()}", [sys.executable, "-m", "skillbus.cli", "sim", *args])
    rc = box.wait(p, 30)
    return rc, (json.loads(p.stdout()) if rc == 0 else p.stderr())


def test_control_services_in_wall_clock_mode(sandbox, binary, tmp_path):
    sim = sandbox.start("sim", [str(binary("sim_server")), "--scene", str(paths.demo_scene()), "--wall-clock",
                                "--speed", "4", "--scenes", str(tmp_path)])
    rc, s0 = sim_cli(sandbox, "status")
    assert rc == 0, s0
    assert not s0["lockstep"] and s0["collision_detector"] == "bullet" and s0["num_objects"] == 3
    initial = sim_cli(sandbox, "reset")[1]["digest"]
    assert sim_cli(sandbox, "pause")[1]["paused"]
    t_paused = sim_cli(sandbox, "status")[1]["sim_time_ns"]
    time.sleep(0.3)
    assert sim_cli(sandbox, "status")[1]["sim_time_ns"] == t_paused, "sim time stands still while paused"
    assert not sim_cli(sandbox, "resume")[1]["paused"]
    time.sleep(0.3)
    assert sim_cli(sandbox, "status")[1]["sim_time_ns"] > t_paused
    assert sim_cli(sandbox, "reset")[1]["digest"] == initial
    rc, err = sim_cli(sandbox, "load-scene", "missing")
    assert rc == 1 and "cannot open the scene file" in err
    # A scene by name from the server's scenes folder; a path is refused before any file is
    # touched (neither whether it exists nor what it begins with comes back).
    for path in ("/etc/passwd", "../demo", str(paths.demo_scene()), ".hidden", "a/b"):
        rc, err = sim_cli(sandbox, "load-scene", path)
        assert rc == 1 and "a name, not a path" in err and "root:" not in err, (path, err)
    assert sim_cli(sandbox, "status")[1]["num_objects"] == 3  # the old world stays
    two = json.loads(paths.demo_scene().read_text())
    two["objects"] = two["objects"][:2]
    f = tmp_path / "two.scene.json"
    scene_file.save(two, f, paths.demo_scene())
    assert sim_cli(sandbox, "load-scene", "two")[1]["num_objects"] == 2
    # A scene of another frame is refused on the wall clock too (its period is fixed at
    # start: the sim time ran at the old period's pace while the physics stepped the new).
    slow = json.loads(paths.demo_scene().read_text())
    slow["physics"]["frame_ms"] = 20.0
    scene_file.save(slow, tmp_path / "slow.scene.json", paths.demo_scene())
    rc, err = sim_cli(sandbox, "load-scene", "slow")
    assert rc == 1 and "the scene's frame (20.000000 ms) differs from the running one (10.000000 ms)" in err, err
    assert sim_cli(sandbox, "status")[1]["num_objects"] == 2  # the world loaded before stays
    sandbox.kill(sim, 15)
    assert sandbox.wait(sim, 15) == 0
    assert last_json(sim.stdout())["ok"]


def test_record_script_is_written_on_the_wall_clock_too_and_refused_at_start_where_it_cannot_be(sandbox, binary,
                                                                                                  tmp_path):
    # Before, --record-script was written only at a lockstep session's end: on the wall
    # clock nothing was written and the run said ok; and a path it could not write to was
    # found out (in the log only, the run still ok) after the whole run.
    recorded = tmp_path / "recorded.json"
    sim = sandbox.start("sim", [str(binary("sim_server")), "--scene", str(paths.demo_scene()), "--wall-clock",
                                "--speed", "4", "--record-script", str(recorded)])
    assert sim_cli(sandbox, "status")[0] == 0
    sandbox.kill(sim, 15)
    assert sandbox.wait(sim, 15) == 0, sim.stderr()[-2000:]
    assert last_json(sim.stdout())["ok"]
    assert json.loads(recorded.read_text()) == {"record_every": 10, "steps": []}  # (no command came)

    nowhere = tmp_path / "afile"
    nowhere.write_text("not a folder")
    refused = sandbox.start("refused", [str(binary("sim_server")), "--scene", str(paths.demo_scene()), "--wall-clock",
                                        "--record-script", str(nowhere / "recorded.json")])
    assert sandbox.wait(refused, 30) == 2
    assert f"cannot start: cannot write the recorded script to {nowhere}/recorded.json: Not a directory" \
        in refused.stderr(), refused.stderr()


def test_pause_is_refused_under_lockstep(sandbox, binary):
    sandbox.start("sim", [str(binary("sim_server")), "--scene", str(paths.demo_scene()),
                          "--participants", "late", "--join-timeout-ms", "20000"])
    rc, s = sim_cli(sandbox, "status")
    assert rc == 0 and s["lockstep"]
    rc, err = sim_cli(sandbox, "pause")
    assert rc == 1 and "pause and resume are for wall-clock mode" in err


def test_pipelined_stepping_and_its_recorded_commands_replay_to_the_same_physics(sandbox, tmp_path):
    """--pipeline steps the physics while the participants work (their commands take
    effect one frame later); --record-script writes the commands as applied, and the
    physics alone replaying them ends bit for bit in the same state."""
    recorded = tmp_path / "applied.json"
    r = run_script_session(sandbox, grasp_lift_release(), 10.0, tmp_path / "piped",
                           sim_args=("--pipeline", "--record-script", str(recorded)))
    assert r["sim"]["ok"] and r["sim"]["commands_accepted"] == 5
    rec = r["record"]
    assert at(rec, 7.4)["objects"]["green"]["pose"][2] - CUBE[2] == pytest.approx(0.10, abs=0.005)  # still lifts
    steps = json.loads(recorded.read_text())["steps"]
    assert [s["at_s"] for s in steps] == pytest.approx([0.01, 2.21, 4.01, 5.01, 7.51])  # one frame after sending
    alone = sandbox.start("alone", [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()),
                                    "--script", str(recorded), "--duration-s", "10"])
    assert sandbox.wait(alone, 120) == 0
    assert last_json(alone.stdout())["state_digest"] == r["sim"]["state_digest"]


def test_recorded_commands_with_velocities_replay_to_the_same_physics(sandbox, tmp_path):
    """A trajectory that gives its velocities (the motion service's do) is recorded with
    them: the follower would derive others, and the replay would follow another path (the
    demo's recordings replayed to another state when the velocities were dropped)."""
    pts = [[1.0, [0.4, 0.0, 1.2, 0.3, 1.2, -0.4], [0.0] * 6],  # (a stop at each point: not what is derived)
           [2.0, [0.8, -0.2, 0.9, 0.6, 1.0, 0.4], [0.0] * 6],
           [3.0, [0.2, 0.1, 1.4, -0.2, 1.5, 0.0], [0.0] * 6]]
    recorded = tmp_path / "applied.json"
    r = run_script_session(sandbox, {"record_every": 10, "steps": [arm(0.5, "sweep", pts)]}, 4.0, tmp_path / "run",
                           sim_args=("--pipeline", "--record-script", str(recorded)))
    assert r["sim"]["ok"] and r["sim"]["commands_accepted"] == 1
    (step,) = json.loads(recorded.read_text())["steps"]
    assert [p[2] for p in step["arm"]["points"]] == [[0.0] * 6] * 3
    alone = sandbox.start("alone", [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()),
                                    "--script", str(recorded), "--duration-s", "4"])
    assert sandbox.wait(alone, 120) == 0
    assert last_json(alone.stdout())["state_digest"] == r["sim"]["state_digest"]
    # Without the velocities the same positions make another trajectory: what the recording
    # would have replayed before.
    derived = tmp_path / "derived.json"
    for p in step["arm"]["points"]:
        del p[2]
    derived.write_text(json.dumps({"steps": [step]}))
    other = sandbox.start("derived", [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()),
                                      "--script", str(derived), "--duration-s", "4"])
    assert sandbox.wait(other, 120) == 0
    assert last_json(other.stdout())["state_digest"] != r["sim"]["state_digest"]


def test_the_benchmarks_grasp_and_carry_touches_no_obstacle_and_puts_the_cube_back(sandbox, tmp_path):
    """bench/sim_physics.py measures a grasp on this script. When the demo scene got its
    post, the script's swing struck it (425 steps of contact) and the bench reported the
    blow as the grasp's slip (15 mm instead of 1): a scenario that measures must check it
    still measures what it says."""
    script = tmp_path / "carry.json"
    script.write_text(json.dumps(grasp_and_carry()))
    p = sandbox.start("carry", [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()),
                                "--script", str(script), "--duration-s", "13"])
    assert sandbox.wait(p, 120) == 0, p.stderr()[-2000:]
    out = last_json(p.stdout())
    assert out["obstacle_contact_steps"] == {"post": 0}, out
    assert math.dist(out["objects"]["green"], CUBE) < 0.002, out["objects"]  # (put back where it was taken)


def tcmalloc_linked() -> bool:
    """Whether the build links sim_server with tcmalloc (SKILLBUS_SIM_TCMALLOC, on unless
    configured off; sim_server/CMakeLists.txt)."""
    cache = (paths.build_dir() / "CMakeCache.txt").read_text()
    return "SKILLBUS_SIM_TCMALLOC:BOOL=OFF" not in cache


def test_the_physics_runs_on_tcmalloc_and_glibcs_allocator_gives_the_same_physics(sandbox, tmp_path):
    """sim_server is linked with tcmalloc (a faster step: docs/sim_server.md). Where a block
    of memory lands must change no number: glibc's allocator (its malloc and libstdc++'s
    operator new put first with LD_PRELOAD, as bench/sim_physics.py compares with) grasps
    and carries to the same state bit for bit."""
    script = tmp_path / "carry.json"
    script.write_text(json.dumps(grasp_and_carry()))
    runs = {}
    for name, env in (("linked", None), ("glibc", {"LD_PRELOAD": "libc.so.6 libstdc++.so.6"})):
        p = sandbox.start(f"carry-{name}", [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()),
                                            "--script", str(script), "--duration-s", "13"], env=env)
        assert sandbox.wait(p, 120) == 0, p.stderr()[-2000:]
        runs[name] = last_json(p.stdout())
    if tcmalloc_linked():
        assert runs["linked"]["allocator"] == "libtcmalloc_minimal.so.4", (
            f"{runs['linked']['allocator']}: sim_server is not on tcmalloc (deploy/setup.sh installs "
            f"libgoogle-perftools-dev; CMake warned if it found no tcmalloc_minimal)")
    else:
        assert runs["linked"]["allocator"] == "libc.so.6 (operator new: libstdc++.so.6)", runs["linked"]
    assert runs["glibc"]["allocator"] == "libc.so.6 (operator new: libstdc++.so.6)", runs["glibc"]["allocator"]
    assert runs["linked"]["state_digest"] == runs["glibc"]["state_digest"]
    assert runs["linked"]["session_digest"] == runs["glibc"]["session_digest"]


def dart_without_assertions() -> tuple[Path | None, str]:
    """The folder of the copy of libdart the build compiled without assertions and the
    physics loads (cmake/DartWithoutAssertions.cmake records it in the CMake cache), or None
    and why not."""
    cache = (paths.build_dir() / "CMakeCache.txt").read_text()
    if "SKILLBUS_DART_WITHOUT_ASSERTIONS:BOOL=OFF" in cache:
        return None, "the build was configured with -DSKILLBUS_DART_WITHOUT_ASSERTIONS=OFF"
    found = re.search(r"^SKILLBUS_DART_LIBRARY_DIR:INTERNAL=(.*)$", cache, re.M)
    if not found or not found.group(1):
        return None, ("the build has no DART without assertions: Debian's source of DART was not fetched "
                      "(deploy/dart-source.sh says why; the build warned), and the physics runs on Debian's "
                      "build with its assertions")
    return Path(found.group(1)), ""


def debians_library_dir() -> Path:
    return Path("/usr/lib") / (sysconfig.get_config_var("MULTIARCH") or "x86_64-linux-gnu")


def test_the_physics_runs_on_dart_without_assertions_and_debians_build_gives_the_same_physics(sandbox, tmp_path):
    """Debian's libdart runs its assertions (NDEBUG undefined); sim_server loads a copy built
    from Debian's source with -O3 -DNDEBUG, a third faster (docs/sim_server.md). Neither an
    assertion nor -O3 may change a number: Debian's own build, put first with
    LD_LIBRARY_PATH, grasps and carries to the same state bit for bit."""
    folder, why_not = dart_without_assertions()
    if folder is None:
        cannot_run(why_not)
    script = tmp_path / "carry.json"
    script.write_text(json.dumps(grasp_and_carry()))
    runs = {}
    for name, env in (("rebuilt", None), ("debian", {"LD_LIBRARY_PATH": str(debians_library_dir())})):
        p = sandbox.start(f"carry-{name}", [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()),
                                            "--script", str(script), "--duration-s", "13"], env=env)
        assert sandbox.wait(p, 120) == 0, p.stderr()[-2000:]
        runs[name] = last_json(p.stdout())
    rebuilt, debian = Path(runs["rebuilt"]["dart"]), Path(runs["debian"]["dart"])
    assert rebuilt.parent.resolve() == folder.resolve(), runs["rebuilt"]["dart"]
    assert debian.parent.resolve() == debians_library_dir().resolve(), runs["debian"]["dart"]
    assert rebuilt.name == debian.name and rebuilt.name.startswith("libdart.so."), (rebuilt, debian)
    assert runs["rebuilt"]["state_digest"] == runs["debian"]["state_digest"]
    assert runs["rebuilt"]["session_digest"] == runs["debian"]["session_digest"]


def test_an_ack_timeout_for_someone_who_is_no_participant_stops_the_start_naming_it(sandbox):
    # Before, the lockstep master refused it only when the session began: an uncaught
    # exception that terminated sim_server.
    sim = sandbox.start("sim", [str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()),
                                "--participants", "a", "--ack-timeout-ms-of", "b=100"])
    assert sandbox.wait(sim, 30) == 2, sim.stderr()[-2000:]
    assert "sim_server: cannot start: --ack-timeout-ms-of names 'b', who is not among --participants" in sim.stderr()


def test_a_reset_starts_the_cameras_over_as_a_fresh_start_would(sandbox, tmp_path):
    # The cameras' noise is drawn from (seed, capture number, pixel): a reset kept counting,
    # so the first capture after it differed from the first capture of a fresh start.
    import numpy as np
    doc = json.loads(paths.demo_scene().read_text())
    doc["cameras"] = [{"name": "overhead", "pose": [0.32, 0.18, 1.6, 1, 0, 0, 0], "width": 80, "height": 60,
                       "fov_deg": 54, "noise_stddev_m": 0.002}]
    scene = scene_file.save(doc, tmp_path / "camera.scene.json", paths.demo_scene())
    sandbox.start("sim", [str(paths.binary("sim_server")), "--scene", str(scene), "--wall-clock"])
    assert sim_cli(sandbox, "status")[0] == 0

    def capture(tag):
        out = tmp_path / f"{tag}.npy"
        p = sandbox.start(f"capture-{tag}", [sys.executable, "-m", "skillbus.cli", "camera", "capture", "overhead",
                                             "--out", str(out)])
        assert sandbox.wait(p, 60) == 0, p.stderr()
        return json.loads(p.stdout().strip().splitlines()[-1])["capture"], np.load(out)

    first, cloud = capture("first")
    capture("second")
    assert sim_cli(sandbox, "reset")[0] == 0
    again, cloud_again = capture("after-reset")
    assert again == first == 0
    # The same noise (2 mm): within 0.1 mm, what the cubes settle by in the meantime (µm).
    assert cloud_again.shape == cloud.shape and np.allclose(cloud_again, cloud, atol=1e-4, rtol=0, equal_nan=True)
