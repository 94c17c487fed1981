"""SkiROS2's skill-class API on skillbus skills: self.params / self._params, self.wmi /
self._wmi, the progress counter (_progress_code, _setProgress, step/success/fail,
startError) as the skill process reports it, self.skill(...) in SkiROS2's forms, and
expand() on the skill process's own instance of the compound. A skill process runs
in-process here on a memq:// bus (no manager: its tick and expand RPC methods are called
directly)."""

from __future__ import annotations

import pytest

from skillbus.msgs import skill_tick_t
from skillbus.skill import (Element, ParallelFf, ParamTypes, PrimitiveBase, Serial, SkillBase, SkillDescription,
                            SkillWrapper, State)
from skillbus.skill import ros_clock
from skillbus.skill.convert import param_msg
from skillbus import tick_context
from tick_messages import in_process, tick_msg


# -- a library (this module is loaded by the skill process) ------------------------------------
class Count(SkillDescription):
    def createDescription(self):
        self.addParam("Until", 4, ParamTypes.Required)
        self.addParam("Target", Element("skiros:Location"), ParamTypes.Optional)


class count_up(PrimitiveBase):
    """Steps while its progress code is below Until: Until + 1 ticks in all."""

    def createDescription(self):
        self.setDescription(Count(), self.__class__.__name__)

    def execute(self):
        if self._progress_code < self.params["Until"].value:
            return self.step("counting")
        return self.success("counted")


class Refuse(SkillDescription):
    pass


class refuse_start(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Refuse(), self.__class__.__name__)

    def onStart(self):
        return self.startError("no gripper", 7)


EXPANDED: list = []  # (label, the object expand ran on, its id(), the Until it saw)


class Outer(SkillDescription):
    def createDescription(self):
        self.addParam("Until", 2, ParamTypes.Optional)


class _keyed(SkillBase):
    """Keys a blackboard entry by id(self), as a skill does to keep a key of its own."""

    def expand(self, skill):
        EXPANDED.append((self.label, self, id(self), self.params["Until"].value))
        skill(self.skill("Count", "count_up", remap={"Until": f"until_{id(self)}"}))


class outer_a(_keyed):
    def createDescription(self):
        self.setDescription(Outer(), self.__class__.__name__)


class outer_b(_keyed):
    def createDescription(self):
        self.setDescription(Outer(), self.__class__.__name__)


def tick(label: str, action: int, instance: int = 1, **values) -> skill_tick_t:
    return tick_msg(label, action, instance=instance, **values)


@pytest.fixture
def process():
    EXPANDED.clear()
    return in_process(__name__)


# -- attributes ---------------------------------------------------------------------------------
def test_params_and_wmi_under_both_names():
    s = count_up()
    assert s.params is s._params and s.params["Until"].value == 4
    world = object()
    s.wmi = world
    assert s._wmi is world and s.wmi is world and s.wm is world
    assert count_up().id != s.id  # SkiROS2's per-object number


def test_progress_counter_as_skiros2():
    s = count_up()
    s._begin()
    assert (s._progress_code, s._progress_msg) == (0, "")
    s._started()
    assert (s.progress_code, s.progress_msg, s.state) == (0, "Start", State.Running)
    assert s.step("a") == State.Running and s._progress_code == 1
    assert s.success("b") == State.Success and (s._progress_code, s._progress_msg) == (2, "b")
    s._setProgress("jump", 10)
    s._setProgress(42)
    assert (s.progress_code, s.progress_msg) == (11, "42") and s.printProgress() == "[11] 42"
    assert s.fail("broken", 3) == State.Failure and s._progress_code == -3  # a positive code is negated
    assert s.fail("broken", -5) == State.Failure and s.code == -5 and s.message == "broken"
    s.setProgress("alias")  # skillbus's public names (SkiROS2 has neither)
    assert s._progress_code == -4
    s.startProgress()
    assert (s._progress_code, s._progress_msg) == (0, "Start")
    assert s.progress_time >= 0.0 and s.progress_period == 0.0


def test_the_process_reports_codes_one_to_n_and_succeeds_on_tick_n():
    proc = in_process(__name__)
    replies = [proc.on_tick(tick("count_up", skill_tick_t.START, Until=10))]
    while replies[-1].state == State.Running and len(replies) < 20:
        replies.append(proc.on_tick(tick("count_up", skill_tick_t.EXECUTE, Until=10)))
    assert [r.code for r in replies] == list(range(1, 12))
    assert [r.state for r in replies] == [State.Running] * 10 + [State.Success]
    assert replies[-1].message == "counted" and replies[0].message == "counting"
    # (SkiROS2's tick calls onEnd once execute has finished: the instance ends in that tick)
    assert [r.ended for r in replies] == [False] * 10 + [True] and proc.instances == {}


def test_start_error_fails_the_start_with_its_message_and_code(process):
    r = process.on_tick(tick("refuse_start", skill_tick_t.START))
    assert (r.state, r.message, r.code) == (State.Failure, "no gripper", -7)


# -- self.skill and the tree --------------------------------------------------------------------
class _compound(SkillBase):
    def createDescription(self):
        self.setDescription(Outer(), "c")


def test_skill_takes_skiros2_type_names_and_specify_after_remap():
    c = _compound()
    assert [c.skill(t).type for t in ("Count", ":Count", "skiros:Count")] == ["Count"] * 3
    node = c.skill("skiros:Count", "count_up", {"Until": "Limit"}, {"Limit": 3})
    assert node.label == "count_up" and node.remaps == {"Until": "Limit"}
    assert node.specified == {"Until": 3}  # SkiROS2 names the remapped parameter by its new name
    group = c.skill(ParallelFf())(c.skill("Count"), c.skill("Count"))
    assert group.type == "" and group.processor.spec() == "ParallelFf" and len(group.children) == 2
    assert group.children[0].parent is group and group.last() is group.children[1]
    with pytest.raises(TypeError, match="must be a condition"):
        c.skill("Count", "", {}, {}, [object()])
    assert c.skill("Count", "", preconditions=[]).type == "Count"


def test_node_conditions_are_the_nodes_own_in_the_skills_keys():
    from skillbus.skill import ConditionIsSpecified, ConditionRelation
    from skillbus.skill.convert import tree_msg
    c = _compound()
    # SkiROS2 code names a remapped key by its new name; the manager wants the skill's own
    by_new = ConditionRelation("Held", "skiros:contain", "Gripper", "Limit", True)
    node = c.skill("Count", "", {"Until": "Limit"}, {}, [by_new])
    node.addHoldCondition(ConditionIsSpecified("Set", "Until", True))
    node.addPostCondition(ConditionIsSpecified("Still", "Until", True))
    (pre,), (hold,), (post,) = node.conditions["pre"], node.conditions["hold"], node.conditions["post"]
    assert (pre.subject_key, pre.object_key) == ("Gripper", "Until") and by_new.object_key == "Limit"  # a copy
    assert hold.subject_key == "Until" and post.label == "Still"
    root = SkillWrapper("Outer")
    root(node)
    n = tree_msg(root).nodes[1]
    assert (n.num_pre, n.num_hold, n.num_post) == (1, 1, 1)
    assert (n.pre[0].kind, n.pre[0].subject, n.pre[0].object, n.pre[0].label) == ("Relation", "Gripper", "Until",
                                                                                "Held")
    assert tree_msg(root).nodes[0].num_pre == 0
    with pytest.raises(NotImplementedError, match="only a skill node"):
        c.skill(ParallelFf()).addPreCondition(by_new)
    with pytest.raises(NotImplementedError, match="latch"):
        root.addChild(c.skill("Count"), latch=True)


def test_wrapper_remap_chains_and_ignores_a_second_remap():
    n = SkillWrapper("Count")
    n.remap("B", "C")
    n.remap("A", "B")  # B is already C: A follows it
    n.remap("A", "D")  # ignored (logged)
    assert n.remaps == {"B": "C", "A": "C"}
    n.specifyParamDefault("C", 1)
    assert n.specified == {"B": 1}
    n.setProcessor(Serial())
    assert n.describe()["processor"] == "Serial"


def test_a_remap_on_the_expanded_skill_itself_is_refused():
    class selfish(_compound):
        def expand(self, skill):
            skill.remap("Until", "Other")
            skill(self.skill("Count"))

    with pytest.raises(ValueError, match="not carried to the manager"):
        selfish().tree()


def test_expand_runs_on_the_loaded_instance_of_each_compound(process):
    a, b = process.loaded["outer_a"], process.loaded["outer_b"]
    for label in ("outer_a", "outer_b", "outer_a"):
        tree = process.on_expand(tick(label, skill_tick_t.EXPAND, Until=5))
        assert tree.error == "", tree.error
    assert [(lbl, obj) for lbl, obj, _, _ in EXPANDED] == [("outer_a", a), ("outer_b", b), ("outer_a", a)]
    ids = [i for _, _, i, _ in EXPANDED]
    assert ids[0] == ids[2] != ids[1]  # keys made from id(self) are the skill's own, run after run
    assert tree.nodes[1].remap_to == [f"until_{id(a)}"]
    process.on_expand(tick("outer_a", skill_tick_t.EXPAND))  # no Until given: the description's again
    assert EXPANDED[-1][3] == 2


# -- SkiROS2's _updateRoutine: element parameters set in a tick go to the world model -------------
class FakeWorld:
    def __init__(self):
        self.written, self.added = [], []

    def write_element_changes(self, e):
        self.written.append(e.id)

    def add_element(self, e):
        self.added.append(e.type)
        out = Element(e.type, e.label, f"{e.type}-9")
        out.mark_loaded()
        return out


class Move(SkillDescription):
    def createDescription(self):
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addParam("Made", Element("skiros:Product"), ParamTypes.Optional)


class move(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Move(), self.__class__.__name__)

    def execute(self):
        obj = self.params["Object"].value
        obj.setProperty("skiros:Weight", 1.5)
        self.params["Object"].value = obj
        return self.success("moved")


def test_element_parameters_set_in_a_tick_are_written():
    s = move()
    s.wmi = FakeWorld()
    cube = Element("skiros:Cube", "red", "skiros:Cube-2")
    cube.mark_loaded()
    s.params["Object"].setValues([cube])
    stamps = s._element_stamps()
    s._updateRoutine(stamps)
    assert s.wmi.written == []  # nothing set during the tick
    s.execute()
    s._updateRoutine(stamps)
    assert s.wmi.written == ["skiros:Cube-2"] and s.wmi.added == []
    # a list whose first element is concrete: an abstract one after it is added and replaced
    stamps = s._element_stamps()
    s.params["Object"].setValues([cube, Element("skiros:Cube", "new")])
    s._updateRoutine(stamps)
    assert s.wmi.added == ["skiros:Cube"] and s.params["Object"].values[1].id == "skiros:Cube-9"
    # an abstract first element: nothing (as SkiROS2)
    stamps = s._element_stamps()
    s.params["Made"].setValues([Element("skiros:Cube")])
    s._updateRoutine(stamps)
    assert s.wmi.added == ["skiros:Cube"]


# -- rospy's clock --------------------------------------------------------------------------------
def test_ros_clock_follows_the_tick_under_lockstep():
    with tick_context.ticking(5, 2_500_000_000):
        start = ros_clock.Time.now()
    with tick_context.ticking(6, 3_000_000_000):
        assert (ros_clock.Time.now() - start).to_sec() == pytest.approx(0.5)
        assert ros_clock.get_time() == pytest.approx(3.0)
    assert ros_clock.Duration(1) < ros_clock.Duration(2) and ros_clock.Time(1) + ros_clock.Duration(1) == ros_clock.Time(2)


def test_param_messages_still_carry_the_values():
    assert [v.i for v in param_msg(count_up().params["Until"]).values] == [4]
