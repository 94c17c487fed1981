"""Several robots on one bus (issue "Cyclone DDS transport, several hosts, several robots"):
each robot's channels under its name, one skill manager per robot, one world model.

* The CLI finds every manager (`skillbus skills` lists each robot's skills) and addresses
  the one it is told to (`--robot NAME`); a run without a robot, when every manager has
  one, fails naming the robots; each manager's skills get its own robot as their Robot.
* `skillbus demo --robots 2`: two arms, each with its gripper on its own CAN bus and its
  own manager, clear six cubes at once in lockstep: exit 0, every cube in a bin in the
  world model and in the physics, the arms never touch, and the same digests on LCM and
  on Cyclone DDS (one digest across runs); the run's log (recorded by skillbus record)
  shows both tasks running at the same time."""

import sys

from conftest import last_json
from skillbus import paths
from test_launch_run_dir import box, netns_procs  # noqa: F401 (box: a fixture)
from test_skills import LIBS, cli, mgr_binary

SCENE = paths.REPO_ROOT / "deploy" / "scenes" / "two_arms.scene.json"
ROBOTS = ("r1", "r2")


def start_robots(sandbox, tmp_path) -> dict[str, str]:
    """A wall-clock world model of the two-arm scene, and per robot a manager and a skill
    process; both processes have the same name (`skills`): each robot's channels are its
    own. Returns the scene's element ids by label."""
    from skillbus.sim.scene import element_ids
    ids = element_ids(SCENE)
    sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", str(tmp_path / "wm"),
                         "--scene", str(SCENE.with_suffix("").with_suffix(".ttl"))])
    procs = []
    for r in ROBOTS:
        sandbox.start(f"{r}_mgr", [mgr_binary(), "--wall-clock", "--robot", r, "--name", f"{r}_skill_mgr"])
        procs.append(sandbox.start(f"{r}_skills", [sys.executable, "-m", "skillbus.cli", "skills-process", "--robot", r,
                                                   "--name", "skills", "--library", "robot_skills",
                                                   "--library", "flow_skills"], env={"PYTHONPATH": str(LIBS)}))
    for p in procs:
        p.wait_for("registered", 30)
    return ids


def test_the_cli_finds_every_robots_manager_and_addresses_the_one_named(sandbox, tmp_path):
    ids = start_robots(sandbox, tmp_path)
    rc, out, err = cli(sandbox, "skills")
    assert rc == 0, out + err
    for r in ROBOTS:  # each manager found its robot in the world model by its name
        assert f"== robot {r}: skill manager {r}_skill_mgr, driving {ids[r]}, " in out, out
    assert out.count("WhoAmI (who_am_i, primitive, process skills)") == 2, out
    rc, out, err = cli(sandbox, "skills", "--json")
    assert rc == 0, err
    listed = {(s["robot"], s["type"]) for s in last_json_list(out)}
    assert {("r1", "WhoAmI"), ("r2", "WhoAmI"), ("r2", "Chain")} <= listed, listed
    rc, out, err = cli(sandbox, "skills", "--robot", "r2")  # one robot's: the list alone
    assert rc == 0 and "== robot" not in out and "WhoAmI (who_am_i" in out, out + err

    for r in ROBOTS:  # each run reaches the manager named, whose skills run for its robot
        rc, out, err = cli(sandbox, "run", "--robot", r, "WhoAmI", "--timeout", "20")
        assert rc == 0, out + err
        assert f"I am {ids[r]}" in out, out

    # A manager drives its own robot: another robot given is refused, naming both (before,
    # r1's arm moved while the skill's conditions and writes named r2's robot).
    rc, out, err = cli(sandbox, "run", "--robot", "r1", "WhoAmI", "-p", f"Robot={ids['r2']}", "--timeout", "20")
    assert rc != 0 and f"parameter Robot: {ids['r2']} is not the robot this manager drives ({ids['r1']};" in out + err, \
        out + err
    rc, out, err = cli(sandbox, "run", "--robot", "r1", "WhoAmI", "-p", f"Robot={ids['r1']}", "--timeout", "20")
    assert rc == 0 and f"I am {ids['r1']}" in out, out + err  # (its own, given: taken)

    rc, out, err = cli(sandbox, "run", "WhoAmI", "--timeout", "20")  # no manager without a robot here
    assert rc == 1, out + err
    assert "the skill managers on this bus are those of the robots r1, r2: name one with --robot NAME" in err, err
    rc, out, err = cli(sandbox, "run", "--robot", "r9", "WhoAmI", "--timeout", "20")
    assert rc == 1 and "r9/SB_SKILL_REQ" in err and "robots r1, r2" in err, err


def test_robot_names_that_cannot_name_a_channel_are_refused(sandbox):
    rc, _, err = cli(sandbox, "run", "--robot", "r/2", "WhoAmI")
    assert rc == 2 and "a letter, then letters, digits or _" in err, err
    p = sandbox.start("mgr", [mgr_binary(), "--wall-clock", "--robot", "2r"])
    assert sandbox.wait(p, 10) == 2 and "--robot" in p.stderr(), p.stderr()
    p = sandbox.start("mgr-env", [mgr_binary(), "--wall-clock"], env={"SKILLBUS_ROBOT": "r/2"})
    assert sandbox.wait(p, 10) == 2 and "$SKILLBUS_ROBOT 'r/2'" in p.stderr(), p.stderr()
    rc, _, err = cli(sandbox, "skills", "--robot", "r 2")
    assert rc == 2 and "a letter, then letters, digits or _" in err, err


def test_a_session_end_waiting_for_someone_who_is_no_participant_is_refused_at_start(sandbox):
    """Else the session could never end when its tasks do (skillbus demo --robots 2 names
    both managers)."""
    p = sandbox.start("sim", [paths.binary("sim_server"), "--scene", str(SCENE), "--participants", "r1_skill_mgr",
                              "--end-when-asked-by", "r1_skill_mgr,r2_skill_mgr"])
    assert sandbox.wait(p, 30) != 0
    assert "--end-when-asked-by names 'r2_skill_mgr', who is not among --participants" in p.stderr(), p.stderr()


def last_json_list(text: str) -> list:
    import json
    return json.loads(text.strip().splitlines()[-1])


def run_demo(box, run_dir, bus: str) -> dict:  # noqa: F811
    demo = box.start(f"demo-{bus}", [sys.executable, "-m", "skillbus.cli", "demo", "--robots", "2", "--json",
                                     "--bus", bus, "--run-dir", str(run_dir)],
                     env={"SKILLBUS_NETNS": "1"})  # (the sandbox is the demo's network namespace)
    rc = box.wait(demo, 600)
    out, err = demo.stdout(), demo.stderr()
    assert "Traceback" not in err, err
    assert rc == 0, f"exit {rc}\n{out[-3000:]}\n{err[-2000:]}"
    assert not netns_procs(box), netns_procs(box)  # the demo shut its system down
    return last_json(out)


def test_two_arms_clear_six_cubes_at_once_the_same_on_lcm_and_dds(box, tmp_path):  # noqa: F811
    runs = {bus: run_demo(box, tmp_path / bus, bus) for bus in ("lcm", "dds")}
    for bus, r in runs.items():
        assert r["ok"], (bus, r["tasks"])
        assert set(r["tasks"]) == {"r1_skill_mgr", "r2_skill_mgr"}
        assert all(t.startswith("Success") for t in r["tasks"].values()), r["tasks"]
        sim = r["sim"]
        assert sim["robots"] == ["r1", "r2"] and sim["robot_contact_steps"] == 0, sim
        assert len(sim["objects"]) == 6 and len(r["world_model"]) == 6
        # Each arm emptied its own table into its own bin (world model and physics agree).
        for name, w in r["world_model"].items():
            region = name[-1]  # red1 ... blue2
            assert w["in"] == f"bin{region}", (bus, name, w)
            p = sim["objects"][name]
            assert abs(p[1] - (0.6 if region == "1" else -1.0)) < 0.15 and p[2] < 0.25, (bus, name, p)
    # Both arms worked at once: in the log of each run (skillbus record's, on either
    # transport), each manager's task runs from the first second to its end, and each
    # ran for most of the other's time; both logs show the same.
    spans = {bus: task_spans(tmp_path / bus / "demo.lcmlog") for bus in runs}
    assert spans["lcm"] == spans["dds"], spans
    assert set(spans["lcm"]) == set(ROBOTS), spans
    (a0, a1), (b0, b1) = spans["lcm"]["r1"], spans["lcm"]["r2"]
    assert a0 < 1.0 and b0 < 1.0 and a1 > 10 and b1 > 10, spans
    assert min(a1, b1) - max(a0, b0) > 0.8 * min(a1 - a0, b1 - b0), spans
    assert runs["lcm"]["sim"]["state_digest"] == runs["dds"]["sim"]["state_digest"]
    assert runs["lcm"]["sim"]["session_digest"] == runs["dds"]["sim"]["session_digest"]


def task_spans(log) -> dict[str, tuple[float, float]]:
    """Per robot: the sim time of its task's first and last progress in an LCM log."""
    import lcm

    from skillbus import auth
    from skillbus.msgs import decode, skill_progress_t
    spans: dict[str, tuple[float, float]] = {}
    for ev in lcm.EventLog(str(log), "r"):
        robot, _, name = ev.channel.rpartition("/")
        if name != "SB_SKILL_PROGRESS":
            continue
        p = decode(skill_progress_t, auth.strip(ev.data))  # (the log keeps the wire's authenticators)
        if p is None:
            continue
        t = p.header.sim_time_ns * 1e-9
        first, _ = spans.get(robot, (t, t))
        spans[robot] = (min(first, t), t)
    return spans
