"""The task planner alone (skillbus.planning): skills and a world built in code, planned
by Fast Downward through Unified Planning. The demo's Pick and Place; a mobile robot that
drives between locations (the shortest plan, optimal mode); goals that cannot be reached
or are malformed; skills left out and why."""

from __future__ import annotations

import pytest

from skillbus.planning import domain as domains
from skillbus.planning.goals import GoalError, parse_goals
from skillbus.planning.model import Condition, SkillSpec, World
from skillbus.planning.solve import PlanError, make_plan, write_pddl
from skillbus.world.ontology_view import OntologyView

CLASSES = {
    "sumo:Object": [], "sumo:Agent": ["sumo:Object"], "skiros:PhysicalObject": ["sumo:Object"],
    "skiros:Location": ["skiros:PhysicalObject"], "skiros:Table": ["skiros:Location"], "skiros:Bin": ["skiros:Location"],
    "skiros:Product": ["skiros:PhysicalObject"], "skiros:Cube": ["skiros:Product"],
    "skiros:Gripper": ["skiros:PhysicalObject"], "skiros:Arm": ["skiros:PhysicalObject"],
    # several parents: the planner keeps the one through which a parameter's concept is reached
    "skiros:Agent": ["skiros:PhysicalObject", "sumo:Agent"], "skiros:Robot": ["skiros:Agent"],
}
ONTOLOGY = OntologyView.from_json({"classes": CLASSES, "relations": {"skiros:contain": [], "skiros:at": []},
                                   "individuals": {}})


def contain(s: str, o: str, desired: bool = True) -> Condition:
    return Condition("Relation", s, o, "skiros:contain", desired=desired)


PICK = SkillSpec("Pick", "pick", [("Gripper", "skiros:Gripper"), ("Arm", "skiros:Arm"), ("Object", "skiros:Product")],
                 pre=[contain("Gripper", "Object", False)], post=[contain("Gripper", "Object")])
PLACE = SkillSpec("Place", "place", [("Gripper", "skiros:Gripper"), ("Arm", "skiros:Arm"), ("Object", "skiros:Product"),
                                     ("Location", "skiros:Location")],
                  pre=[contain("Gripper", "Object")], post=[contain("Location", "Object")])
GRASP = SkillSpec("Grasp", "grasp", [("Gripper", "skiros:Gripper"), ("Object", "skiros:Product")],
                  pre=[contain("Gripper", "Object", False)], post=[contain("Gripper", "Object")], for_planning=False)
MOVE = SkillSpec("MoveArm", "move_arm", [("Arm", "skiros:Arm"), ("Target", "skiros:PhysicalObject")])


def demo_world() -> World:
    types = {"skiros:Table-1": "skiros:Table", "skiros:Cube-2": "skiros:Cube", "skiros:Cube-3": "skiros:Cube",
             "skiros:Cube-4": "skiros:Cube", "skiros:Bin-5": "skiros:Bin", "skiros:Gripper-7": "skiros:Gripper",
             "skiros:Arm-8": "skiros:Arm"}
    relations = {("skiros:Table-1", "skiros:contain", f"skiros:Cube-{i}") for i in (2, 3, 4)}
    return World(types, {}, relations, ONTOLOGY)


def test_the_demos_pick_and_place_reach_two_cubes_in_the_bin():
    plan = make_plan([PICK, PLACE, GRASP, MOVE], demo_world(),
                     "(skiros:contain skiros:Bin-5 skiros:Cube-2), (skiros:contain skiros:Bin-5 skiros:Cube-4)")
    assert [s.skill.type for s in plan.steps] == ["Pick", "Place", "Pick", "Place"]
    placed = {s.params["Object"] for s in plan.steps if s.skill.type == "Place"}
    assert placed == {"skiros:Cube-2", "skiros:Cube-4"}
    for s in plan.steps:
        assert s.params["Gripper"] == "skiros:Gripper-7" and s.params["Arm"] == "skiros:Arm-8"
        if s.skill.type == "Place":
            assert s.params["Location"] == "skiros:Bin-5"
    # Each Pick comes right before the Place of its cube.
    assert [s.params["Object"] for s in plan.steps[0::2]] == [s.params["Object"] for s in plan.steps[1::2]]
    assert plan.left_out == {"grasp": "it is not available for planning (available_for_planning = False)",
                             "move_arm": "it has no post-condition: nothing for the planner to reach with it"}


def test_a_goal_already_true_needs_no_step_and_the_same_request_the_same_plan():
    w = demo_world()
    assert make_plan([PICK, PLACE], w, "(skiros:contain skiros:Table-1 skiros:Cube-3)").steps == []
    goal = "(skiros:contain skiros:Bin-5 skiros:Cube-3), (skiros:contain skiros:Gripper-7 skiros:Cube-2)"
    runs = [[str(s) for s in make_plan([PICK, PLACE], w, goal).steps] for _ in range(2)]
    assert runs[0] == runs[1] and len(runs[0]) == 3


# -- a mobile manipulator -----------------------------------------------------------------
def at(s: str, o: str, desired: bool = True) -> Condition:
    return Condition("Relation", s, o, "skiros:at", desired=desired)


DRIVE = SkillSpec("Drive", "drive", [("Robot", "skiros:Robot"), ("From", "skiros:Location"), ("To", "skiros:Location")],
                  pre=[at("Robot", "From")], post=[at("Robot", "From", False), at("Robot", "To")])
FETCH = SkillSpec("Fetch", "fetch", [("Robot", "skiros:Robot"), ("Object", "skiros:Product"), ("At", "skiros:Location")],
                  pre=[at("Robot", "At"), contain("At", "Object"), contain("Robot", "Object", False)],
                  post=[contain("Robot", "Object")])
DROP = SkillSpec("Drop", "drop", [("Robot", "skiros:Robot"), ("Object", "skiros:Product"), ("At", "skiros:Location")],
                 pre=[at("Robot", "At"), contain("Robot", "Object")], post=[contain("At", "Object")])


def warehouse() -> World:
    """Four shelves in a row; the robot at the first; a cube on each of the other three."""
    types = {"skiros:Robot-1": "skiros:Robot", **{f"skiros:Table-{i}": "skiros:Table" for i in (2, 3, 4, 5)},
             "skiros:Cube-6": "skiros:Cube", "skiros:Cube-7": "skiros:Cube", "skiros:Cube-8": "skiros:Cube"}
    relations = {("skiros:Robot-1", "skiros:at", "skiros:Table-2"), ("skiros:Table-3", "skiros:contain", "skiros:Cube-6"),
                 ("skiros:Table-4", "skiros:contain", "skiros:Cube-7"), ("skiros:Table-5", "skiros:contain", "skiros:Cube-8")}
    return World(types, {}, relations, ONTOLOGY)


def test_a_mobile_robot_gets_the_shortest_plan_for_three_goals_at_once():
    # Every cube to the first table. The robot may carry several things, so the shortest
    # plan collects all three on one trip: three drives out (table 3, 4, 5 in some order),
    # three fetches, one drive back, three drops: 10 skills. A plan that brings each cube
    # back on its own takes more.
    goal = ", ".join(f"(skiros:contain skiros:Table-2 skiros:Cube-{i})" for i in (6, 7, 8))
    optimal = make_plan([DRIVE, FETCH, DROP], warehouse(), goal, optimal=True)
    kinds = [s.skill.type for s in optimal.steps]
    assert kinds.count("Fetch") == 3 and kinds.count("Drop") == 3
    assert kinds.count("Drive") == 4  # out to 3, 4, 5 (three drives), and back (one)
    assert len(optimal.steps) == 10 and optimal.engine == "fast-downward-opt"
    # The plan is executable: replay it on the facts.
    where, holds, cubes = "skiros:Table-2", set(), {"skiros:Cube-6": "skiros:Table-3", "skiros:Cube-7": "skiros:Table-4",
                                                   "skiros:Cube-8": "skiros:Table-5"}
    for s in optimal.steps:
        if s.skill.type == "Drive":
            assert s.params["From"] == where
            where = s.params["To"]
        elif s.skill.type == "Fetch":
            assert s.params["At"] == where == cubes[s.params["Object"]]
            holds.add(s.params["Object"])
            cubes[s.params["Object"]] = "robot"
        else:
            assert s.params["At"] == where and s.params["Object"] in holds
            holds.discard(s.params["Object"])
            cubes[s.params["Object"]] = where
    assert set(cubes.values()) == {"skiros:Table-2"}
    # A satisficing plan reaches the goals too, perhaps with more steps.
    assert len(make_plan([DRIVE, FETCH, DROP], warehouse(), goal).steps) >= 10


def test_goals_that_cannot_be_reached_are_named():
    w = demo_world()
    # No skill puts anything into a cube.
    with pytest.raises(PlanError, match=r"reaches \(skiros:contain skiros:Cube-2 skiros:Cube-3\) from the world"):
        make_plan([PICK, PLACE], w, "(skiros:contain skiros:Bin-5 skiros:Cube-4), (skiros:contain skiros:Cube-2 skiros:Cube-3)")
    # Each alone, not both: an element is in one container.
    with pytest.raises(PlanError, match=r"each goal can be reached on its own, but not all 2 together"):
        make_plan([PICK, PLACE], w, "(skiros:contain skiros:Bin-5 skiros:Cube-4), (skiros:contain skiros:Table-1 skiros:Cube-4)")
    # Without Pick nothing leaves the table; the message names the skills it had.
    with pytest.raises(PlanError, match=r"no sequence of the skills \(place\) reaches"):
        make_plan([PLACE, GRASP], w, "(skiros:contain skiros:Bin-5 skiros:Cube-4)")


def test_malformed_goals_and_unknown_names_are_refused_naming_them():
    w = demo_world()
    with pytest.raises(GoalError, match=r"no goal"):
        make_plan([PICK, PLACE], w, " ")
    with pytest.raises(GoalError, match=r"goal 2 '\(skiros:contain skiros:Bin-5': a '\(' is not closed"):
        make_plan([PICK, PLACE], w, "(skiros:contain skiros:Bin-5 skiros:Cube-4), (skiros:contain skiros:Bin-5")
    with pytest.raises(GoalError, match=r"the world model has no element skiros:Cube-99"):
        make_plan([PICK, PLACE], w, "(skiros:contain skiros:Bin-5 skiros:Cube-99)")
    with pytest.raises(GoalError, match=r"no skill the planner can use has skiros:near in its conditions "
                                        r"\(the predicates it knows: skiros:contain\)"):
        make_plan([PICK, PLACE], w, "(skiros:near skiros:Bin-5 skiros:Cube-4)")
    with pytest.raises(GoalError, match=r"skiros:contain takes 2 element\(s\)"):
        make_plan([PICK, PLACE], w, "(skiros:contain skiros:Bin-5)")
    with pytest.raises(GoalError, match=r"a fact names a predicate and one or two elements, not 3"):
        parse_goals("(skiros:contain a b c)")


def test_conditions_become_preconditions_and_effects(tmp_path):
    """Properties, types and disjunctions; what cannot be expressed leaves the skill out."""
    prop = lambda owl, value, d=True, op="=", o="": Condition("Property", "Object", "", owl, op, value, d, o)  # noqa: E731
    paint = SkillSpec("Paint", "paint", [("Object", "skiros:Product")],
                      pre=[prop("skiros:Color", "red", o="c"), prop("skiros:Color", "blue", o="c"),
                           prop("skiros:Weight", 1.0, op="<"), Condition("OnType", "Object", "", "skiros:Cube")],
                      post=[prop("skiros:Color", "green")])
    weigh = SkillSpec("Weigh", "weigh", [("Object", "skiros:Product")], post=[prop("skiros:Weight", 2.0, op=">")])
    typed = SkillSpec("Retype", "retype", [("Object", "skiros:Product")],
                      post=[Condition("OnType", "Object", "", "skiros:Cube")])
    w = demo_world()
    w.properties = {"skiros:Cube-2": {"skiros:Color": ["red"], "skiros:Weight": [0.2]},
                    "skiros:Cube-3": {"skiros:Color": ["white"], "skiros:Weight": [0.2]},
                    "skiros:Cube-4": {"skiros:Color": ["blue"], "skiros:Weight": [5.0]}}
    plan = make_plan([paint, weigh, typed], w, "(skiros:Color=green skiros:Cube-2)")
    assert [str(s) for s in plan.steps] == ["Paint (paint) Object=skiros:Cube-2"]
    assert plan.left_out == {"weigh": "its post-condition skiros:Weight > 2.0 does not say which value results",
                             "retype": "its post-condition OnType skiros:Cube is not a fact a skill can make true"}
    with pytest.raises(PlanError):  # white, not red or blue
        make_plan([paint], w, "(skiros:Color=green skiros:Cube-3)")
    with pytest.raises(PlanError):  # too heavy
        make_plan([paint], w, "(skiros:Color=green skiros:Cube-4)")
    # Painting it green makes it no longer red; the files Fast Downward reads.
    d = domains.build([paint], w, parse_goals("(not (skiros:Color=red skiros:Cube-2))"))
    dom, prob = write_pddl(d, tmp_path)
    text = dom.read_text()
    assert "(or (skiros_color_red ?object) (skiros_color_blue ?object))" in text.lower().replace("=", "_")
    assert prob.read_text().count("(:init") == 1


def test_what_the_ontology_allows_is_not_what_the_world_has():
    # An AbstractRelation condition (may a Location contain a Product?) and a Relation
    # (does it?) were one fluent: with the abstract one's skill first, every allowed pair
    # began true, so "Cube-2 in Bin-5" was reached by an empty plan (the task succeeded and
    # the robot did nothing); with it last, the abstract check read the real containment.
    stow = SkillSpec("Stow", "a_stow", [("Location", "skiros:Location"), ("Object", "skiros:Product")],
                     pre=[Condition("AbstractRelation", "Location", "Object", "skiros:contain")],
                     post=[Condition("HasProperty", "Object", "", "skiros:Stowed")])
    w = demo_world()
    w.may_relate = lambda s, r, o: True
    goal = "(skiros:contain skiros:Bin-5 skiros:Cube-2)"
    want = [str(x) for x in make_plan([PICK, PLACE], w, goal).steps]
    assert len(want) == 2
    for skills in ([stow, PICK, PLACE], [PICK, PLACE, stow]):
        assert [str(x) for x in make_plan(skills, w, goal).steps] == want, [sk.label for sk in skills]
    plan = make_plan([stow], w, "(has:skiros:Stowed skiros:Cube-2)")  # the abstract check itself holds
    assert [x.skill.label for x in plan.steps] == ["a_stow"]


def test_comparisons_of_one_property_with_one_value_are_facts_of_their_own():
    # Weight<1.0 and Weight>1.0 were both the fluent skiros_Weight_1.0: building the
    # problem failed ("already defined"), and every plan of that manager with it.
    prop = lambda owl, value, op="=": Condition("Property", "Object", "", owl, op, value, True)  # noqa: E731
    light = SkillSpec("LiftLight", "lift_light", [("Object", "skiros:Product")],
                      pre=[prop("skiros:Weight", 1.0, "<")], post=[prop("skiros:Lifted", True)])
    heavy = SkillSpec("Push", "push", [("Object", "skiros:Product")],
                      pre=[prop("skiros:Weight", 1.0, ">")], post=[prop("skiros:Pushed", True)])
    same = SkillSpec("Weigh", "weigh", [("Object", "skiros:Product")],
                     pre=[prop("skiros:Weight", 1.0, "=")], post=[prop("skiros:Weighed", True)])
    w = demo_world()
    w.properties = {"skiros:Cube-2": {"skiros:Weight": [0.2]}, "skiros:Cube-4": {"skiros:Weight": [5.0]}}
    assert [x.skill.label for x in make_plan([light, heavy, same], w, "(skiros:Lifted=true skiros:Cube-2)").steps] == \
        ["lift_light"]
    assert [x.skill.label for x in make_plan([light, heavy, same], w, "(skiros:Pushed=true skiros:Cube-4)").steps] == \
        ["push"]
    with pytest.raises(PlanError):  # Cube-4 is not light
        make_plan([light, heavy, same], w, "(skiros:Lifted=true skiros:Cube-4)")


def test_the_time_limit_ends_the_search_naming_it():
    # A warehouse of 30 shelves and 60 cubes, 15 cubes to bring home: more than 50 ms of work.
    types = {"skiros:Robot-1": "skiros:Robot", **{f"skiros:Table-{i}": "skiros:Table" for i in range(2, 32)}}
    relations = {("skiros:Robot-1", "skiros:at", "skiros:Table-2")}
    for i in range(60):
        cube = f"skiros:Cube-{100 + i}"
        types[cube] = "skiros:Cube"
        relations.add((f"skiros:Table-{3 + i % 29}", "skiros:contain", cube))
    w = World(types, {}, relations, ONTOLOGY)
    goal = ", ".join(f"(skiros:contain skiros:Table-2 skiros:Cube-{100 + 4 * i})" for i in range(15))
    with pytest.raises(PlanError, match=r"no plan within the planner's time limit of 0.05 s \(fast-downward\) "
                                        r"for 15 goal\(s\)"):
        make_plan([DRIVE, FETCH, DROP], w, goal, time_limit=0.05)


def test_a_failed_plan_still_writes_its_pddl_and_a_failing_planner_is_one_line(tmp_path, monkeypatch):
    # Before, --pddl wrote nothing when there was no plan (when it is needed most), and a
    # planner that could not run (UPNoRequestedEngineAvailableException, no message) or
    # ended out of memory was a traceback or "no sequence of the skills reaches ...".
    from types import SimpleNamespace

    from unified_planning.engines import PlanGenerationResultStatus as S

    from skillbus.planning import solve
    w = demo_world()
    with pytest.raises(PlanError, match="no plan"):
        make_plan([PICK], w, "(skiros:contain skiros:Bin-5 skiros:Cube-2)", pddl_dir=tmp_path / "pddl")
    assert "(:action pick" in (tmp_path / "pddl" / "domain.pddl").read_text().lower()
    assert (tmp_path / "pddl" / "problem.pddl").read_text()

    class NoEngine(Exception):
        pass

    def no_engine(problem, optimal, time_limit):
        raise NoEngine()

    monkeypatch.setattr(solve, "_solve_with_engine", no_engine)
    with pytest.raises(PlanError) as e:
        make_plan([PICK, PLACE], w, "(skiros:contain skiros:Bin-5 skiros:Cube-2)")
    assert str(e.value) == "the planner fast-downward failed: NoEngine"
    monkeypatch.setattr(solve, "_solve_with_engine", lambda problem, optimal, time_limit: SimpleNamespace(
        status=S.MEMOUT, log_messages=[SimpleNamespace(message="search ran out of memory")]))
    with pytest.raises(PlanError) as e:
        make_plan([PICK, PLACE], w, "(skiros:contain skiros:Bin-5 skiros:Cube-2)")
    assert str(e.value) == "the planner fast-downward ended with MEMOUT for 1 goal(s): search ran out of memory"


def test_the_explanation_of_no_plan_keeps_within_the_time_limit(monkeypatch):
    # Before, each goal was tried again with the whole time limit: (goals + 1) x the limit,
    # and a goal that timed out on its own was said to be unreachable. The engine is a
    # stand-in that uses up what it is given (a clock of its own: no sleeping here).
    from types import SimpleNamespace

    from unified_planning.engines import PlanGenerationResultStatus as S

    from skillbus.planning import solve
    clock = [100.0]
    asked: list[float] = []

    def engine(uses: float, status_of):
        def run(problem, optimal, time_limit):
            asked.append(round(time_limit, 3))
            clock[0] += min(uses, time_limit)
            return SimpleNamespace(status=status_of(len(asked)), log_messages=[])
        return run

    monkeypatch.setattr(solve.time, "monotonic", lambda: clock[0])
    goals = "(skiros:contain skiros:Bin-5 skiros:Cube-2), (skiros:contain skiros:Bin-5 skiros:Cube-4)"
    # the search proves there is no plan after 0.5 s; the goals alone each time out
    monkeypatch.setattr(solve, "_solve_with_engine",
                        engine(0.5, lambda n: S.UNSOLVABLE_INCOMPLETELY if n == 1 else S.TIMEOUT))
    with pytest.raises(PlanError) as e:
        make_plan([PICK, PLACE], demo_world(), goals, time_limit=2.0)
    assert asked == [2.0, 1.5, 1.0], asked  # 2 s in all
    assert "not decided within the time limit, on its own: (skiros:contain skiros:Bin-5 skiros:Cube-2), " \
           "(skiros:contain skiros:Bin-5 skiros:Cube-4)" in str(e.value), str(e.value)
    assert "no sequence" not in str(e.value)
    # the search itself used the whole limit: nothing is left to explain with
    asked.clear()
    monkeypatch.setattr(solve, "_solve_with_engine", engine(2.0, lambda n: S.UNSOLVABLE_INCOMPLETELY))
    with pytest.raises(PlanError) as e:
        make_plan([PICK, PLACE], demo_world(), goals, time_limit=2.0)
    assert asked == [2.0] and "not decided within the time limit" in str(e.value), (asked, str(e.value))


def test_an_optional_element_no_condition_names_is_not_bound_by_the_planner():
    # Before, every optional element parameter was bound like a required one: without an
    # element of its concept the skill was unusable (and not listed as left out); with
    # some, one was picked at random (Dock=skiros:Bin-3).
    from skillbus.msgs import skill_condition_t, skill_description_t, skill_param_t
    from skillbus.planning.model import skill_from_msg

    def param(key, concept, kind):
        p = skill_param_t()
        p.key, p.data_type, p.concept, p.param_type = key, "element", concept, kind
        return p

    d = skill_description_t()
    d.type, d.label = "Charge", "charge"
    d.params = [param("Robot", "skiros:Robot", skill_param_t.REQUIRED), param("Dock", "skiros:Location",
                skill_param_t.OPTIONAL), param("Via", "skiros:Location", skill_param_t.OPTIONAL)]
    d.num_params = 3
    c = skill_condition_t()
    c.kind, c.subject, c.owl, c.desired_state = "HasProperty", "Robot", "skiros:Charged", True
    pre = skill_condition_t()
    pre.kind, pre.subject, pre.owl, pre.desired_state = "HasProperty", "Via", "skiros:Open", True
    d.post, d.num_post, d.pre, d.num_pre = [c], 1, [pre], 1
    spec = skill_from_msg(d)
    assert spec.params == [("Robot", "skiros:Robot"), ("Via", "skiros:Location")]  # Dock: the manager's to fill
    d.pre, d.num_pre = [], 0  # no condition names Via now either
    spec = skill_from_msg(d)
    w = World({"skiros:Robot-1": "skiros:Robot"}, {}, set(), ONTOLOGY)  # no Location at all
    assert [str(x) for x in make_plan([spec], w, "(has:skiros:Charged skiros:Robot-1)").steps] == \
        ["Charge (charge) Robot=skiros:Robot-1"]


def test_a_class_with_two_parents_is_still_a_parameter_of_either():
    # A planning type has one parent. skiros:Robot is below sumo:Agent and (through
    # skiros:Agent) skiros:PhysicalObject; with a skill on PhysicalObjects added, the Robot
    # kept the other parent, and Charge (a sumo:Agent) could no longer take it: "no plan".
    hp = lambda key, owl: Condition("HasProperty", key, "", owl)  # noqa: E731
    charge = SkillSpec("Charge", "charge", [("Robot", "sumo:Agent")], post=[hp("Robot", "skiros:Charged")])
    inspect = SkillSpec("Inspect", "inspect", [("Target", "skiros:PhysicalObject")],
                        post=[hp("Target", "skiros:Inspected")])
    w = World({"skiros:Robot-1": "skiros:Robot", "skiros:Cube-2": "skiros:Cube"}, {}, set(), ONTOLOGY)
    for skills in ([charge], [charge, inspect], [inspect, charge]):
        assert [str(x) for x in make_plan(skills, w, "(has:skiros:Charged skiros:Robot-1)").steps] == \
            ["Charge (charge) Robot=skiros:Robot-1"], [sk.label for sk in skills]
    assert [str(x) for x in make_plan([charge, inspect], w, "(has:skiros:Inspected skiros:Cube-2)").steps] == \
        ["Inspect (inspect) Target=skiros:Cube-2"]
    with pytest.raises(PlanError):  # a cube is no agent: the ontology's check holds
        make_plan([charge, inspect], w, "(has:skiros:Charged skiros:Cube-2)")


def test_plans_made_at_once_from_one_folder_are_each_their_own(tmp_path, monkeypatch):
    # Fast Downward wrote its translated task to output.sas in the current folder: two
    # plans at once from one folder (two skill processes under supervisord, two test
    # workers) read each other's task: another problem's plan, or an engine error.
    import concurrent.futures
    import os
    monkeypatch.chdir(tmp_path)
    w = demo_world()
    goals = {"(skiros:contain skiros:Bin-5 skiros:Cube-2)": "skiros:Cube-2",
             "(skiros:contain skiros:Bin-5 skiros:Cube-4)": "skiros:Cube-4"}

    def plan(goal: str) -> str:
        return make_plan([PICK, PLACE], w, goal).steps[0].params["Object"]

    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        for _ in range(3):
            order = list(goals) * 2
            assert list(pool.map(plan, order)) == [goals[g] for g in order]
    assert not os.listdir(tmp_path), os.listdir(tmp_path)  # nothing written here
