"""`--json` on every listing command, parsed here, through the real processes: the skill
manager (C++) with a skill process, the world model server, the physics server; and
every command that needs a server and gets no answer says so in one line naming it."""

import json
import sys
from pathlib import Path

import can

from skillbus import paths
from test_skills import LIBS, mgr_binary

REPO = Path(__file__).resolve().parents[2]
SCENE_TTL = REPO / "deploy" / "scenes" / "demo.ttl"


def skillbus(box, *args, timeout=60):
    """`skillbus ARGS` inside the sandbox: (exit code, stdout, stderr)."""
    p = box.start(f"cli-{args[0]}-{len(box.procs)}", [sys.executable, "-m", "skillbus.cli", *map(str, args)],
                  env={"PYTHONPATH": str(LIBS)})
    rc = box.wait(p, timeout)
    return rc, p.stdout(), p.stderr()


def system(sandbox, tmp_path):
    """A world model with the demo scene, the manager, and a process with the condition
    and flow test skills."""
    sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", tmp_path / "wm", "--scene", SCENE_TTL])
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    proc = sandbox.start("proc1", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "proc1",
                                   "--library", "condition_skills", "--library", "flow_skills", "--world-model"],
                         env={"PYTHONPATH": str(LIBS)})
    proc.wait_for("registered", 30)


def test_skills_json_has_every_parameter_with_kind_type_defaults_and_every_condition(sandbox, tmp_path):
    system(sandbox, tmp_path)
    rc, out, err = skillbus(sandbox, "skills", "--json")
    assert rc == 0, err
    listed = json.loads(out)
    assert [(s["type"], s["label"]) for s in listed] == sorted((s["type"], s["label"]) for s in listed)  # as the text
    assert {s["label"] for s in listed if s["type"] == "PickUp"} == {"a_pickup_cylinder", "b_pickup_cube"}
    skills = {s["type"]: s for s in listed}
    mode = skills["Mode"]
    assert (mode["label"], mode["compound"], mode["process"]) == ("mode", False, "proc1")
    assert mode["params"][0] == {"key": "Mode", "kind": "Required", "data_type": "str", "concept": "",
                                 "defaults": ["open"], "options": [], "description": ""}
    assert {p["key"]: p["defaults"] for p in skills["Produce"]["params"]}["Ticks"] == [2]
    assert skills["Chain"]["compound"] is True
    ground = {p["key"]: p for p in skills["GroundMe"]["params"]}
    assert ground["Gripper"]["kind"] == "Inferred" and ground["Gripper"]["data_type"] == "element"
    assert ground["Gripper"]["concept"] == "skiros:Gripper"
    assert ground["Gripper"]["defaults"] == [{"id": "", "type": "skiros:Gripper", "label": ""}]
    assert skills["CheckProperty"]["pre"] == [
        {"kind": "Property", "label": "High", "subject": "Subject", "object": "", "owl": "skiros:PositionZ",
         "desired_state": True, "op": ">", "value": 0.4, "or_label": ""}]
    rel = skills["CheckRelation"]["pre"][0]
    assert (rel["kind"], rel["subject"], rel["object"], rel["owl"], rel["value"]) == \
        ("Relation", "Subject", "Object", "skiros:contain", None)
    assert [c["label"] for c in skills["Hold"]["hold"]] == ["StillOnTable"]
    # the text lists the same skills
    rc, text, _ = skillbus(sandbox, "skills")
    assert rc == 0 and all(f"{t} (" in text for t in skills)


def test_run_json_prints_the_result_and_the_final_tree(sandbox, tmp_path):
    system(sandbox, tmp_path)
    rc, out, err = skillbus(sandbox, "run", "Chain", "--json", "--timeout", "30")
    assert rc == 0, out + err
    r = json.loads(out)  # stdout is one JSON object: "task 1: Chain started" went to stderr
    assert "task 1: Chain started" in err
    assert (r["task"], r["skill"], r["state"], r["ended"], r["exit_code"]) == (1, "Chain", "Success", True, 0)
    root, nodes = r["tree"][0], r["tree"]
    assert root["parent"] == -1 and root["type"] == "Chain" and root["state"] == "Success"
    assert {n["type"] for n in nodes} >= {"Produce", "Consume", "Mode", "Fails"}
    consumes = [n for n in nodes if n["type"] == "Consume"]
    assert {n["params"]["Item"] for n in consumes} >= {"widget-7", "fixed"}
    assert next(n for n in nodes if n["type"] == "Fails")["code"] == -3
    # a failure: the exit code and the state say so; --watch --json: one JSON line per shown tree
    rc, out, err = skillbus(sandbox, "run", "Wait", "-p", "Ticks=3", "--watch", "--json", "--timeout", "30")
    lines = [json.loads(line) for line in out.splitlines()]
    assert rc == 0 and len(lines) >= 2, out + err
    assert all(x["task"] == 2 and "nodes" in x for x in lines[:-1])
    assert lines[-2]["state"] == "Success" and lines[-1]["state"] == "Success" and lines[-1]["tree"]
    # --detach --json: the task as JSON
    rc, out, err = skillbus(sandbox, "run", "Wait", "-p", "Ticks=1000", "--detach", "--json")
    assert rc == 0 and json.loads(out) == {"task": 3, "skill": "Wait", "detached": True}, out + err
    assert skillbus(sandbox, "stop", "3")[0] == 0


def test_wm_tree_json_is_the_containment_tree_with_positions(sandbox, tmp_path):
    sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", tmp_path / "wm", "--scene", SCENE_TTL])
    rc, out, err = skillbus(sandbox, "wm", "--timeout", "20", "tree", "--json")
    assert rc == 0, err
    roots = json.loads(out)

    def walk(nodes, parent=None):
        for n in nodes:
            yield parent, n
            yield from walk(n["children"], n["id"])

    where = {n["id"]: (parent, n) for parent, n in walk(roots)}
    parent, cube = where["skiros:Cube-2"]
    assert where[parent][1]["type"] == "skiros:Table"
    assert cube["type"] == "skiros:Cube" and cube["label"] == "red" and not cube["cycle"]
    assert len(cube["position"]) == 3 and all(isinstance(x, float) for x in cube["position"])
    assert {p for p, _ in where.values()} - set(where) == {None}  # one tree: every parent is in it
    # the text shows the same tree
    rc, text, _ = skillbus(sandbox, "wm", "--timeout", "20", "tree")
    assert rc == 0 and len(text.splitlines()) == len(where)
    assert any(line.strip().startswith("skiros:Cube-2 [red] at (") for line in text.splitlines())


def test_sim_json_also_for_the_digest(sandbox, binary):
    sandbox.start("sim", [str(binary("sim_server")), "--scene", str(paths.demo_scene()), "--wall-clock"])
    rc, out, err = skillbus(sandbox, "sim", "status", "--timeout", "20")
    assert rc == 0 and json.loads(out)["num_objects"] == 3, err
    rc, out, err = skillbus(sandbox, "sim", "digest", "--json")
    assert rc == 0, err
    digest = json.loads(out)["digest"]
    assert len(digest) == 64 and int(digest, 16) >= 0
    rc, out, _ = skillbus(sandbox, "sim", "digest")
    assert rc == 0 and len(out.strip()) == 64  # without --json: the digest alone


def test_can_log_json_lists_every_frame_decoded(tmp_path):
    import subprocess
    log = tmp_path / "traffic.log"
    with can.Logger(str(log)) as w:
        for i, (cid, data) in enumerate([(0x705, b"\x00"), (0x705, b"\x05"), (0x085, b"\x10\x82\x01\x00\x00\x00\x00\x00")]):
            w.on_message_received(can.Message(timestamp=100.0 + i * 0.5, arbitration_id=cid, data=data,
                                              is_extended_id=False, channel="vcan0"))
    r = subprocess.run([sys.executable, "-m", "skillbus.cli", "can-log", str(log), "--json"], capture_output=True,
                       text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    frames = json.loads(r.stdout)
    assert [(f["t"], f["id"], f["data"]) for f in frames] == [(0.0, 0x705, "00"), (0.5, 0x705, "05"),
                                                             (1.0, 0x085, "1082010000000000")]
    assert frames[0]["decoded"] == "boot-up" and frames[1]["decoded"].startswith("heartbeat")
    assert frames[2]["decoded"].startswith("EMCY 0x8210")
    text = subprocess.run([sys.executable, "-m", "skillbus.cli", "can-log", str(log)], capture_output=True, text=True,
                          timeout=60).stdout.splitlines()
    assert [line.split()[-1] for line in text][:1] == ["boot-up"] and len(text) == 3


def test_lockstep_session_json(tmp_path):
    import subprocess
    r = subprocess.run([sys.executable, "-m", "skillbus.cli", "lockstep-session", "--frames", "50", "--python", "1",
                        "--cpp", "1", "--json"], capture_output=True, text=True, timeout=120)
    s = json.loads(r.stdout)  # stdout is the summary alone
    assert r.returncode == 0 and s["ok"] and s["frames"] == 50, r.stdout + r.stderr
    assert set(s["participant_results"]) == {"py1", "cpp1"}


# -- a command without its server: one line naming the server and its channel -------------

def one_line(err: str) -> str:
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    return err.strip()


def test_wm_without_a_world_model_server_names_it(sandbox):
    rc, out, err = skillbus(sandbox, "wm", "--timeout", "1", "tree", "--json")
    assert rc == 1 and out == ""
    assert one_line(err) == ("error: no world model server answered on SB_WM_REQ within 1 s: "
                             "is the system running, in this network namespace?")


def test_sim_without_a_physics_server_names_it(sandbox):
    rc, out, err = skillbus(sandbox, "sim", "status", "--timeout", "1")
    assert rc == 1 and out == ""
    assert one_line(err) == ("error: no physics server answered on SB_SIM_REQ within 1 s: "
                             "is the system running, in this network namespace?")


def test_skills_without_a_skill_manager_names_it(sandbox):
    for args in (["skills", "--json"], ["run", "Wait", "--json"]):
        rc, out, err = skillbus(sandbox, *args)
        assert rc == 1 and out == ""
        assert one_line(err) == ("error: no skill manager answered on SB_SKILL_REQ within 2 s: "
                                 "is the system running, in this network namespace?")
