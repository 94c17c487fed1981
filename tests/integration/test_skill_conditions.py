"""Conditions and grounding against a live world model (wm_server with the demo scene);
each condition kind is also judged by Python's Condition.evaluate on the same world, which
must agree with the manager."""

import json
import sys
from pathlib import Path

import pytest

from test_skills import LIBS, cli, start_system, start_wm

REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent


def start_condition_system(sandbox, data):
    """The demo's world model (in `data`), a wall-clock manager and condition_skills."""
    start_wm(sandbox, data, scene=REPO / "deploy" / "scenes" / "demo.ttl")
    start_system(sandbox, "condition_skills", world_model=True)
    return sandbox


@pytest.fixture
def system(sandbox, tmp_path):
    return start_condition_system(sandbox, tmp_path / "wm")


CASES = [
    # skill, params that make it hold, params that do not, label
    ("CheckHasProperty", ["Subject=skiros:Cube-2"], ["Subject=skiros:Table-1"], "HasSize"),
    ("CheckProperty", ["Subject=skiros:Cube-2"], ["Subject=skiros:Bin-5"], "High"),
    ("CheckRelation", ["Subject=skiros:Table-1", "Object=skiros:Cube-2"],
     ["Subject=skiros:Bin-5", "Object=skiros:Cube-2"], "Contains"),
    ("CheckAbstractRelation", ["Subject=skiros:Table-1", "Object=skiros:Cube-2"],
     ["Subject=skiros:Cube-2", "Object=skiros:Table-1"], "MayContain"),
    ("CheckIsSpecified", ["Subject=skiros:Cube-2"], [], "Given"),
    ("CheckGenerate", ["Subject=skiros:Cube-2"], [], "Made"),
    ("CheckOnType", ["Subject=skiros:Cube-3"], ["Subject=skiros:Table-1"], "IsProduct"),
]


def python_verdict(system, skill, params) -> bool:
    """Whether the condition holds by Condition.evaluate(params, wmi) in Python, on the
    same world (condition_probe.py): it must agree with the manager's check."""
    p = system.start(f"probe-{skill}-{len(system.procs)}", [sys.executable, str(HERE / "condition_probe.py"), skill,
                                                           *params], env={"PYTHONPATH": str(LIBS)})
    assert system.wait(p, 30) == 0, p.stderr()
    verdicts = json.loads(p.stdout().strip().splitlines()[-1])
    assert len(verdicts) == 1, verdicts
    return next(iter(verdicts.values()))


@pytest.mark.parametrize("skill,good,bad,label", CASES, ids=[c[0] for c in CASES])
def test_each_condition_true_and_false(system, skill, good, bad, label):
    rc, out, err = cli(system, "run", skill, *[x for p in good for x in ("-p", p)], "--timeout", "20")
    assert rc == 0, out + err
    assert python_verdict(system, skill, good), f"Python's evaluate says {label} fails; the manager ran {skill}"
    rc, out, err = cli(system, "run", skill, *[x for p in bad for x in ("-p", p)], "--timeout", "20")
    assert rc == 1 and f"pre-condition {label}" in out and "failed" in out, out + err
    assert not python_verdict(system, skill, bad), f"Python's evaluate says {label} holds; the manager refused it"


def test_grounding_fills_inferred_and_abstract_parameters_jointly(system):
    rc, out, _ = cli(system, "run", "GroundMe", "--timeout", "20")
    assert rc == 0, out
    assert "Gripper=skiros:Gripper-7" in out and "Object=skiros:Cube-2" in out and "Table=skiros:Table-1" in out


def test_grounding_that_finds_nothing_names_the_parameter(system):
    # Cube-2 moves into the bin and the others are removed: nothing on the table any more.
    code = ("from skillbus.bus import open_bus; from skillbus.world import WorldModelInterface as W; "
            "w = W(open_bus(), 't'); w.set_relation('skiros:Table-1','skiros:contain','skiros:Cube-2', False); "
            "w.remove_element('skiros:Cube-3'); w.remove_element('skiros:Cube-4')")
    p = system.start("edit", [sys.executable, "-c", code])
    assert system.wait(p, 30) == 0, p.stderr()
    rc, out, _ = cli(system, "run", "GroundMe", "--timeout", "20")
    assert rc == 1 and "cannot ground parameter Object (skiros:Product)" in out, out


def test_a_broken_hold_condition_stops_a_running_primitive(system):
    run = system.start("run", [sys.executable, "-m", "skillbus.cli", "run", "Hold", "-p", "Object=skiros:Cube-3",
                               "--timeout", "30", "--watch"], env={"PYTHONPATH": str(LIBS)})
    run.wait_for("holding", 20, stream="stdout")  # (the primitive runs: its hold-condition is checked each tick)
    code = ("from skillbus.bus import open_bus; from skillbus.world import WorldModelInterface as W; "
            "W(open_bus(), 't').set_relation('skiros:Table-1','skiros:contain','skiros:Cube-3', False)")
    edit = system.start("edit", [sys.executable, "-c", code])
    assert system.wait(edit, 30) == 0
    assert system.wait(run, 30) == 1
    out = run.stdout()
    assert "hold-condition StillOnTable failed" in out, out
    assert "held" not in out


def test_without_a_label_the_implementation_that_can_start_is_taken(system):
    rc, out, _ = cli(system, "run", "PickUp", "--timeout", "20")
    assert rc == 0 and "cube skiros:Cube-2" in out, out  # a_pickup_cylinder cannot ground a cylinder
    rc, out, _ = cli(system, "run", "PickUp", "--label", "a_pickup_cylinder", "--timeout", "20")
    assert rc == 1 and "cannot ground parameter Object" in out, out


def test_infer_invalid_re_grounds_what_a_round_made_invalid(system):
    # Each round moves Object to the bin; its OnTable pre-condition then fails, so
    # InferInvalid grounds Object again: the next cube on the table.
    rc, out, _ = cli(system, "run", "Clear", "--verbose", "--timeout", "30")
    assert rc == 0, out
    assert 'Moved=["skiros:Cube-2", "skiros:Cube-3", "skiros:Cube-4"]' in out, out
