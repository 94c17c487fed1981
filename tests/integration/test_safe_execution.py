"""Safe skill execution through the real processes (wm_server, skill_mgr, a skill process,
the CLI): a wrong value fails the start naming it and never becomes another value; what a
skill writes reaches the blackboard and the world model exactly; a check that must stop a
skill stops it before it acts."""

import sys
import time
from pathlib import Path

import pytest

from test_skills import LIBS, cli, mgr_binary

REPO = Path(__file__).resolve().parents[2]


def start_process(sandbox, name="proc1", *extra):
    proc = sandbox.start(name, [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", name,
                                "--library", "safety_skills", "--library", "skillbus.skills.manipulation",
                                "--world-model", *extra], env={"PYTHONPATH": str(LIBS)})
    proc.wait_for("registered", 30)
    return proc


@pytest.fixture
def system(sandbox, tmp_path):
    from skillbus import paths
    sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", tmp_path / "wm",
                         "--scene", REPO / "deploy" / "scenes" / "demo.ttl"])
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    sandbox.proc1 = start_process(sandbox)
    return sandbox


def run(system, *args, timeout="20"):
    return cli(system, "run", *args, "--timeout", timeout)


# ---- 1. a wrong element parameter is never replaced ---------------------------------
def test_a_missing_element_fails_the_start_and_is_not_replaced(system):
    rc, out, err = run(system, "Inspect", "-p", "Object=skiros:Cube-99")
    assert rc == 1, out + err
    assert "parameter Object: no element skiros:Cube-99 in the world model (expected a skiros:Product)" in out, out
    assert "Cube-2" not in out  # the first cube was the silent substitute


def test_an_id_without_its_prefix_fails_and_names_the_element_meant(system):
    rc, out, err = run(system, "Inspect", "-p", "Object=Cube-3")
    assert rc == 1, out + err
    assert "no element Cube-3 in the world model" in out and "did you mean skiros:Cube-3?" in out, out


def test_an_element_of_the_wrong_type_fails_the_start(system):
    rc, out, err = run(system, "Inspect", "-p", "Object=skiros:Table-1")
    assert rc == 1, out + err
    assert "parameter Object: skiros:Table-1 is a skiros:Table, not a skiros:Product" in out, out


def test_a_missing_element_after_the_world_copy_is_loaded_is_still_an_error(system):
    # The reported case: once the manager has its world copy (a task that needed grounding),
    # a wrong id became the first cube.
    rc, out, _ = run(system, "Echo")
    assert rc == 0, out
    rc, out, _ = run(system, "Inspect", "-p", "Object=skiros:Cube-99")
    assert rc == 1 and "no element skiros:Cube-99" in out, out


def test_an_ambiguous_required_element_is_not_grounded_to_an_arbitrary_one(system):
    rc, out, _ = run(system, "Inspect")
    assert rc == 1, out
    assert "cannot ground parameter Object: 3 elements are a skiros:Product" in out, out
    assert "give one (Object=ID)" in out


def test_move_arm_with_a_wrong_or_no_target_never_moves(system):
    # The arm is unique in the scene (grounded); the target is not: neither run may reach
    # the skill (which would fail differently: this process has no arm).
    rc, out, _ = run(system, "MoveArm", "-p", "Target=skiros:Cube-99")
    assert rc == 1 and "parameter Target: no element skiros:Cube-99" in out, out
    rc, out, _ = run(system, "MoveArm")
    assert rc == 1 and "cannot ground parameter Target:" in out and "skiros:PhysicalObject" in out, out
    assert "Arm-8" not in out.split("cannot ground")[0]
    assert "no arm" not in out


# ---- 5. element parameters arrive with their properties -----------------------------
def test_a_fresh_manager_hands_elements_with_their_properties(system):
    rc, out, err = run(system, "Inspect", "-p", "Object=skiros:Cube-3")
    assert rc == 0, out + err
    assert "skiros:Cube-3 is green at z=" in out, out


# ---- 9. a user's value wins over a static value; strict parsing ---------------------
def test_a_users_value_overrides_a_required_default(system):
    rc, out, _ = run(system, "Echo", "-p", "N=5")
    assert rc == 0 and "N=5 Flag=False" in out, out
    rc, out, _ = run(system, "Echo")
    assert rc == 0 and "N=1 Flag=False" in out, out


@pytest.mark.parametrize("text,value", [("true", True), ("TRUE", True), ("1", True), ("False", False), ("0", False)])
def test_bools_parse_strictly(system, text, value):
    rc, out, _ = run(system, "Echo", "-p", f"Flag={text}")
    assert rc == 0 and f"Flag={value}" in out, out


@pytest.mark.parametrize("param", ["Flag=maybe", "Flag=yes", "Flag=", "N=5.5", "N=five"])
def test_a_value_that_is_not_of_its_type_is_refused(system, param):
    rc, out, err = run(system, "Echo", "-p", param)
    assert rc == 2, out + err
    assert "error:" in err and param.split("=")[0] in err, err
    assert "started" not in out


def test_the_manager_refuses_a_forged_start_of_the_wrong_type_or_key(system):
    code = r'''
import sys
from skillbus.bus import open_bus
from skillbus.msgs import skill_param_t, skill_start_t, skill_task_t, skill_value_t
from skillbus.rpc import RpcClient, RpcRemoteError
c = RpcClient(open_bus(), "SKILL", "forger")
def start(key, data_type, value):
    req = skill_start_t(); req.type = "Echo"
    p = skill_param_t(); p.key, p.data_type = key, data_type
    p.values = [value]; p.num_values = 1
    req.params = [p]; req.num_params = 1
    try:
        c.call("start", req, skill_task_t, timeout=5.0)
        print("accepted")
    except RpcRemoteError as e:
        print("refused:", e)
v = skill_value_t(); v.type = skill_value_t.STRING; v.s = "5"
start("N", "int", v)
start("NN", "int", v)
'''
    p = system.start("forge", [sys.executable, "-c", code])
    assert system.wait(p, 30) == 0, p.stderr()
    lines = p.stdout().strip().splitlines()
    assert lines[0].startswith("refused:") and "parameter N of Echo is a int, not a str" in lines[0], lines
    assert lines[1].startswith("refused:") and "Echo has no parameter NN" in lines[1], lines


# ---- 8. an emptied value reaches the blackboard -------------------------------------
def test_a_consumer_that_empties_its_queue_finishes(system):
    rc, out, err = run(system, "FillAndDrain", "--verbose", timeout="30")
    assert rc == 0, out + err
    assert "drained in 4 ticks" in out, out


# ---- 12. what a compound's tree fixes for its children is checked (and item 1's siblings)
TREES = [
    # skill, exit code, what the result must say
    ("BadRemap", 1, "remap Inn -> Out: Echo has no parameter Inn"),          # a remap of a missing key
    ("BadSpecify", 1, "specify NN: Echo has no parameter NN"),               # a specify of a missing key
    ("BadSpecifyType", 1, "specify N: parameter N of Echo is a int, not a str"),  # of the wrong type
    ("CountTwo", 0, "2 items: ['a', 'b']"),                                   # a specified list: one list
    ("Greet", 0, "greeting ready"),                                           # onInit on the running instance
]


@pytest.mark.parametrize("skill,code,said", TREES, ids=[t[0] for t in TREES])
def test_trees_and_instances(system, skill, code, said):
    rc, out, _ = run(system, skill)
    assert rc == code and said in out, out


# ---- 13. a hold-condition false at start ---------------------------------------------
def test_a_hold_condition_false_at_start_stops_the_skill_before_it_acts(system):
    # Cube-2 is on the table; the bin holds nothing: Object=Cube-2 holds, and a cube that
    # is taken off the table does not.
    code = ("from skillbus.bus import open_bus; from skillbus.world import WorldModelInterface as W; "
            "W(open_bus(), 't').set_relation('skiros:Table-1','skiros:contain','skiros:Cube-3', False)")
    edit = system.start("edit", [sys.executable, "-c", code])
    assert system.wait(edit, 30) == 0, edit.stderr()
    rc, out, _ = run(system, "HoldOnTable", "-p", "Object=skiros:Cube-3")
    assert rc == 1 and "hold-condition OnTable" in out, out
    time.sleep(0.3)  # the process's log is line-buffered: anything it printed is there by now
    assert "EXECUTED hold_on_table" not in system.proc1.stderr()


# ---- 7. an update of an element parameter keeps the world's relations ----------------
def test_updating_an_element_parameter_keeps_its_relations(system):
    rc, out, err = run(system, "Relabel", "-p", "Object=skiros:Cube-2")
    assert rc == 0, out + err
    code = ("from skillbus.bus import open_bus; from skillbus.world import WorldModelInterface as W; "
            "w = W(open_bus(), 't'); e = w.get_element('skiros:Cube-2'); "
            "print(e.label, w.get_relations('', 'skiros:contain', 'skiros:Cube-2'), "
            "e.hasProperty('skiros:PositionZ'))")
    p = system.start("check", [sys.executable, "-c", code])
    assert system.wait(p, 30) == 0, p.stderr()
    out = p.stdout()
    assert out.startswith("red-seen "), out
    assert "'src': 'skiros:Table-1'" in out, out  # still on the table
    assert out.strip().endswith("True"), out     # and still with its pose


def test_set_parent_keeps_the_world_pose(system):
    # Poses are relative to the container: moving Cube-2 from the table into the bin must
    # re-express its pose, not leave the table-relative numbers under the bin.
    code = ("from skillbus.bus import open_bus; from skillbus.world import WorldModelInterface as W; "
            "from skillbus.world.poses import world_pose; "
            "w = W(open_bus(), 't'); before = world_pose(w, 'skiros:Cube-2')[0]; "
            "w.set_parent('skiros:Cube-2', 'skiros:Bin-5'); after = world_pose(w, 'skiros:Cube-2')[0]; "
            "print(w.get_relations('', 'skiros:contain', 'skiros:Cube-2')[0]['src'], "
            "max(abs(a - b) for a, b in zip(before, after)))")
    p = system.start("check", [sys.executable, "-c", code])
    assert system.wait(p, 30) == 0, p.stderr()
    parent, moved = p.stdout().split()
    assert parent == "skiros:Bin-5" and float(moved) < 1e-6, p.stdout()


def test_a_processor_the_manager_does_not_know_is_reported_at_registration_and_expansion(system):
    proc = system.start("fancy", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "fancy",
                                  "--library", "fancy_processor_skills"], env={"PYTHONPATH": str(LIBS)})
    proc.wait_for("registered", 30)
    assert "processor Fancy (fancy_processor_skills) is not known to the skill manager (it knows: " in proc.stderr()
    assert "processor Invert" not in proc.stderr()  # every standard class has its C++ counterpart
    rc, out, _ = run(system, "UsesFancy")
    assert rc == 1 and "unknown processor 'Fancy' (known: InferInvalid, Invert(processor), Loop(n)" in out, out
