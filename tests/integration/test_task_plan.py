"""Task planning against the real parts: a wall-clock world model server with the
warehouse world (warehouse.ttl: a robot at the first of four shelves, a cube on each
other one), a skill manager and a skill process serving the warehouse skills (Drive,
Fetch, Drop: skiros:at and skiros:contain conditions) and TaskPlan. `skillbus plan` finds
the shortest plan for three goals; `skillbus run TaskPlan` runs it; a cube moved by hand
mid-plan makes a step fail and TaskPlan plan again; goals that cannot be reached, or are
malformed, fail naming why."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from test_skills import LIBS, cli, start_system, start_wm

HERE = Path(__file__).resolve().parent
ALL_HOME = ", ".join(f"(skiros:contain skiros:Table-2 skiros:Cube-{i})" for i in (6, 7, 8))


@pytest.fixture
def warehouse(sandbox, tmp_path):
    start_wm(sandbox, tmp_path / "wm", scene=HERE / "warehouse.ttl")
    start_system(sandbox, "warehouse_skills", "skillbus.skills.planning", world_model=True)
    return sandbox


def where(box, eid: str) -> str:
    rc, out, err = cli(box, "wm", "get", eid, "--json")
    assert rc == 0, err
    e = json.loads(out)
    return next(s for s, p, o in e["relations"] if p == "skiros:contain" and o == eid)


def test_skillbus_plan_finds_the_shortest_plan_for_three_goals(warehouse, tmp_path):
    rc, out, err = cli(warehouse, "plan", ALL_HOME, "--optimal", "--json", "--pddl", tmp_path / "pddl")
    assert rc == 0, err
    plan = json.loads(out.strip().splitlines()[-1])
    kinds = [s["type"] for s in plan["steps"]]
    # three drives out, three fetches, one drive back, three drops
    assert len(kinds) == 10 and kinds.count("Drive") == 4, plan
    assert plan["engine"] == "fast-downward-opt"
    assert {"drive", "fetch", "drop"} <= {s["label"] for s in plan["steps"]}
    assert plan["left_out"]["task_plan"] == "it is not available for planning (available_for_planning = False)"
    domain = (tmp_path / "pddl" / "domain.pddl").read_text()
    assert "(:action drive" in domain and "skiros_at" in domain
    # The human form names every step.
    rc, out, err = cli(warehouse, "plan", "(skiros:contain skiros:Table-2 skiros:Cube-6)")
    assert rc == 0 and "4 step(s)" in out and "1. Drive (drive) Mover=skiros:Robot-1 From=skiros:Table-2 To=skiros:Table-3" \
        in out, out + err


def test_task_plan_runs_the_plan(warehouse):
    rc, out, err = cli(warehouse, "run", "TaskPlan", "-p", f"Goal={ALL_HOME}", "-p", "Optimal=true", "--timeout", "120",
                       timeout=150)
    assert rc == 0, out + err
    for cube in (6, 7, 8):
        assert where(warehouse, f"skiros:Cube-{cube}") == "skiros:Table-2"


def test_a_step_that_fails_because_the_world_changed_makes_task_plan_plan_again(warehouse):
    # As the robot leaves for the red cube's shelf, the cube is moved to the last shelf:
    # Fetch's pre-condition (the cube on the shelf the robot is at) fails; TaskPlan plans
    # again from the world as it is and fetches the cube there.
    mover = warehouse.start("mover", [sys.executable, str(HERE / "move_when_driving.py"), "skiros:Robot-1",
                                      "skiros:Cube-6", "skiros:Table-5", "60"])
    rc, out, err = cli(warehouse, "run", "TaskPlan", "-p", "Goal=(skiros:contain skiros:Table-2 skiros:Cube-6)",
                       "--watch", "--timeout", "120", timeout=150)
    assert warehouse.wait(mover, 30) == 0, mover.stdout() + mover.stderr()
    assert rc == 0, out + err
    assert where(warehouse, "skiros:Cube-6") == "skiros:Table-2"
    assert "Fetch failed: pre-condition OnShelf failed" in out, out  # the first plan's Fetch, refused
    assert "(RetryOnFail(1)) Success: succeeded at attempt 2" in out, out  # the second plan, to where the cube is now


def test_task_plan_plans_with_the_skills_of_every_process_of_its_manager(sandbox, tmp_path):
    # TaskPlan in one skill process, the warehouse skills in another: it plans with what the
    # manager has registered, not only with its own process's skills.
    start_wm(sandbox, tmp_path / "wm", scene=HERE / "warehouse.ttl")
    start_system(sandbox, "skillbus.skills.planning", name="planner", world_model=True)
    other = sandbox.start("movers", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "movers",
                                     "--library", "warehouse_skills", "--world-model"], env={"PYTHONPATH": str(LIBS)})
    other.wait_for("registered", 30)
    rc, out, err = cli(sandbox, "run", "TaskPlan", "-p", "Goal=(skiros:contain skiros:Table-2 skiros:Cube-7)",
                       "--timeout", "120", timeout=150)
    assert rc == 0, out + err
    assert where(sandbox, "skiros:Cube-7") == "skiros:Table-2"


def test_goals_that_cannot_be_reached_or_are_malformed_fail_naming_why(warehouse):
    rc, out, err = cli(warehouse, "run", "TaskPlan", "-p", "Goal=(skiros:contain skiros:Cube-7 skiros:Cube-6)",
                       "--timeout", "60", timeout=90)
    assert rc == 1 and "no plan: no sequence of the skills (drive, drop, fetch) reaches " \
        "(skiros:contain skiros:Cube-7 skiros:Cube-6)" in out + err, out + err
    rc, out, err = cli(warehouse, "run", "TaskPlan", "-p", "Goal=(skiros:contain skiros:Table-2", "--timeout", "60",
                       timeout=90)
    assert rc == 1 and "a '(' is not closed" in out + err, out + err
    rc, out, err = cli(warehouse, "plan", "(skiros:contain skiros:Table-2 skiros:Cube-99)")
    assert rc == 2 and "the world model has no element skiros:Cube-99" in err, out + err
    rc, out, err = cli(warehouse, "plan", "(skiros:near skiros:Table-2 skiros:Cube-6)")
    assert rc == 2 and "no skill the planner can use has skiros:near in its conditions" in err, out + err
    rc, out, err = cli(warehouse, "plan", "(skiros:contain skiros:Table-2 skiros:Cube-6)", "--time-limit", "0")
    assert rc == 2 and "argument --time-limit: '0' is not a number of seconds greater than 0" in err, out + err



def test_a_long_expansion_keeps_the_process_and_the_manager_heard(warehouse):
    # An expansion that plans may take seconds. Before, the skill process sent no heartbeat
    # meanwhile (the manager dropped its skills after 3 s: the next run found "unknown
    # skill ... (available: none)"), and the manager, waiting for it, did not announce
    # itself (the CLI gave the task up: "the skill manager went silent"). Now the process
    # beats from a thread of its own and the manager announces while it waits.
    rc, out, err = cli(warehouse, "run", "Ponder", "--timeout", "60", timeout=90)
    assert rc == 0 and "Ponder" in out and "Success" in out, out + err
    rc, out, err = cli(warehouse, "skills")
    assert rc == 0 and "Drive (drive" in out and "TaskPlan (task_plan" in out, out + err
