"""SkiROS2's condition tests (skiros2_common/src/test/test_conditions.py), case by case, on
skillbus.skill.conditions; then evaluate against a world model (an in-memory stand-in of
the world model interface: the same rules as the skill manager's check,
skill_mgr/src/conditions.cpp), setTrue / revert, setDesiredState and the rest of the API."""

import pytest
from world_standin import WorldStandIn

# SkiROS2: skiros2_common.core.world_element, .params and .conditions
from skillbus.skill import (AbstractConditionRelation, ConditionGenerate, ConditionHasProperty, ConditionIsSpecified,
                            ConditionOnType, ConditionOr, ConditionProperty, ConditionRelation, Element, ParamHandler,
                            ParamOptions, ParamTypes, SkillDescription)
from skillbus.skill.convert import condition_msgs


@pytest.fixture
def setup():
    """An abstract element with Float = 0.0 as the required parameter Param1, and two
    conditions on it: Float = 0 and Float > 0."""
    e = Element("Type")
    e.setProperty("Float", 0.0)
    ph = ParamHandler()
    ph.addParam("Param1", e, ParamTypes.Required)
    equal_zero = ConditionProperty("Example", "Float", "Param1", "=", 0.0, True)
    above_zero = ConditionProperty("Example", "Float", "Param1", ">", 0.0, True)
    return e, ph, equal_zero, above_zero


# ---- the upstream cases (all without a world model: wmi=None) -----------------------------------
def test_ConditionOr(setup):
    e, ph, equal_zero, above_zero = setup
    at_least_zero = ConditionOr(True)
    at_least_zero.addCondition(above_zero)
    at_least_zero.addCondition(equal_zero)
    assert at_least_zero.evaluate(ph, None)
    e.setProperty("Float", 1.0)  # the parameter holds this very element
    assert at_least_zero.evaluate(ph, None)
    e.setProperty("Float", -1.0)
    assert not at_least_zero.evaluate(ph, None)


def test_ConditionProperty(setup):
    _, ph, equal_zero, above_zero = setup
    assert equal_zero.evaluate(ph, None)
    assert not above_zero.evaluate(ph, None)
    assert ConditionProperty("Example", "Float", "Param1", ">", -1.0, True).evaluate(ph, None)


def test_ConditionHasProperty(setup):
    e, required, _, _ = setup
    optional = ParamHandler()
    optional.addParam("Param1", e, ParamTypes.Optional)
    has_float = ConditionHasProperty("Example", "Float", "Param1", True)
    assert not has_float.evaluate(required, None)  # abstract and required: cannot tell
    assert has_float.evaluate(optional, None)      # abstract and optional: need not have it
    e.setUri("1")
    assert has_float.evaluate(required, None)
    e.getProperty("Float").unset()                 # there, without a value
    assert not has_float.evaluate(required, None)
    e.removeProperty("Float")
    assert not has_float.evaluate(required, None)


def test_ConditionIsSpecified(setup):
    e, ph, _, _ = setup
    given = ConditionIsSpecified("Example", "Param1", True)
    assert not given.evaluate(ph, None)
    e.setUri("1")
    assert given.evaluate(ph, None)


# ---- against a world model: the skill manager's rules ------------------------------------------
@pytest.fixture
def world():
    w = WorldStandIn(superclasses={"skiros:Cube": "skiros:Product", "skiros:Product": "skiros:PhysicalObject",
                                   "skiros:Table": "skiros:Location", "skiros:Location": "skiros:PhysicalObject"},
                     superproperties={"skiros:contain": "skiros:spatiallyRelated"},
                     may_relate={("skiros:Location", "skiros:contain", "skiros:Product")})
    w.table = w.add("skiros:Table", "table")
    w.cube = w.add("skiros:Cube", "red", skiros_Size=0.05, skiros_PositionZ=0.8)
    w.bin = w.add("skiros:Location", "bin", skiros_PositionZ=0.1)
    w.set_relation(w.table.id, "skiros:contain", w.cube.id)
    return w


def params(world, subject=None, object=None, kind=ParamTypes.Optional) -> ParamHandler:
    """Subject and Object element parameters (of `kind`), given by world id or left abstract."""
    ph = ParamHandler()
    for key, eid in (("Subject", subject), ("Object", object)):
        ph.addParam(key, Element("skiros:PhysicalObject"), kind)
        if eid is not None:
            ph.specify(key, world.get_element(eid))
    return ph


def test_each_kind_true_and_false_against_the_world(world):
    cases = [  # condition, parameters under which it holds, under which it does not
        (ConditionHasProperty("HasSize", "skiros:Size", "Subject", True), [world.cube.id], [world.table.id]),
        (ConditionProperty("High", "skiros:PositionZ", "Subject", ">", 0.4, True), [world.cube.id], [world.bin.id]),
        (ConditionRelation("Contains", "skiros:contain", "Subject", "Object", True),
         [world.table.id, world.cube.id], [world.bin.id, world.cube.id]),
        (ConditionRelation("Near", "skiros:spatiallyRelated", "Subject", "Object", True),  # a subproperty counts
         [world.table.id, world.cube.id], [world.cube.id, world.table.id]),
        (AbstractConditionRelation("MayContain", "skiros:contain", "Subject", "Object", True),
         [world.table.id, world.cube.id], [world.cube.id, world.table.id]),
        (ConditionIsSpecified("Given", "Subject", True), [world.cube.id], []),
        (ConditionGenerate("Made", "Subject", True), [world.cube.id], []),
        (ConditionOnType("IsProduct", "Subject", "skiros:Product"), [world.cube.id], [world.table.id]),
    ]
    for c, good, bad in cases:
        assert c.evaluate(params(world, *good), world), c.label
        assert not c.evaluate(params(world, *bad), world), c.label


def test_the_world_copy_counts_not_the_parameter_copy(world):
    ph = params(world, world.cube.id, kind=ParamTypes.Required)
    ph.getParamValue("Subject").setProperty("skiros:PositionZ", 0.0)  # changed in the parameter only
    assert ConditionProperty("High", "skiros:PositionZ", "Subject", ">", 0.4, True).evaluate(ph, world)
    assert not ConditionProperty("High", "skiros:PositionZ", "Subject", ">", 0.4, True).evaluate(ph, None)


def test_what_cannot_be_judged_fails_whatever_the_desired_state(world):
    required_abstract = params(world, kind=ParamTypes.Required)
    for desired in (True, False):
        for c in (ConditionHasProperty("x", "skiros:Size", "Subject", desired),
                  ConditionProperty("x", "skiros:Size", "Subject", "=", 0.05, desired),
                  ConditionRelation("x", "skiros:contain", "Subject", "Object", desired),
                  ConditionOnType("x", "Subject", "skiros:Product", desired)):
            assert not c.evaluate(required_abstract, world), (c, desired)
    # an element that is not (any more) in the world
    gone = params(world, world.cube.id, world.table.id, kind=ParamTypes.Required)
    world.remove_element(world.cube.id)
    assert not ConditionRelation("x", "skiros:contain", "Subject", "Object", False).evaluate(gone, world)
    assert not ConditionHasProperty("x", "skiros:Size", "Subject", False).evaluate(gone, world)
    # no such parameter
    assert not ConditionIsSpecified("x", "Nope", False).evaluate(gone, world)


def test_an_unset_optional_parameter_is_not_judged(world):
    unset = params(world, None, world.cube.id)  # Subject optional and abstract
    for desired in (True, False):
        assert ConditionRelation("x", "skiros:contain", "Subject", "Object", desired).evaluate(unset, world)
        assert ConditionHasProperty("x", "skiros:Size", "Subject", desired).evaluate(unset, world)
    # ... but IsSpecified asks exactly that, and in a ConditionOr every member is judged
    assert not ConditionIsSpecified("x", "Subject", True).evaluate(unset, world)
    either = ConditionOr(ConditionRelation("x", "skiros:contain", "Subject", "Object", True),
                         ConditionIsSpecified("y", "Object", False))
    assert not either.evaluate(unset, world)


def test_property_comparison_as_the_manager(world):
    e = world.add("skiros:Cube", "c", skiros_Count=3, skiros_Name="red", skiros_Flag=True)
    ph = params(world, e.id)

    def holds(owl, op, value, desired=True):
        return ConditionProperty("x", owl, "Subject", op, value, desired).evaluate(ph, world)
    assert holds("skiros:Count", "=", 3.0) and holds("skiros:Count", ">=", 3) and holds("skiros:Count", "<", 3.5)
    assert holds("skiros:Name", "=", "red") and holds("skiros:Name", "!=", "blue")
    assert not holds("skiros:Name", ">", "a")                      # text is not ordered
    assert holds("skiros:Flag", "=", True) and not holds("skiros:Flag", "=", 1)
    assert not holds("skiros:Missing", "=", 1) and holds("skiros:Missing", "=", 1, desired=False)


def test_or_against_the_world(world):
    ph = params(world, world.bin.id, world.cube.id)
    c = ConditionOr(ConditionRelation("InBin", "skiros:contain", "Subject", "Object", True),
                    ConditionHasProperty("HasSize", "skiros:Size", "Object", True))
    assert c.evaluate(ph, world)
    c.conditions[1] = ConditionHasProperty("HasColor", "skiros:Color", "Object", True)
    assert not c.evaluate(ph, world)
    assert ConditionOr(False).evaluate(ph, world)  # SkiROS2: no member holds, which is desired


# ---- setTrue / revert (SkiROS2's simulation) -----------------------------------------------------
def test_setTrue_and_revert_a_relation(world):
    ph = params(world, world.bin.id, world.cube.id, kind=ParamTypes.Required)
    inside = ConditionRelation("InBin", "skiros:contain", "Subject", "Object", True)
    assert not inside.revert(ph, world)  # nothing to undo yet
    assert not inside.evaluate(ph, world)
    assert inside.setTrue(ph, world) and inside.evaluate(ph, world)
    world.set_relation(world.table.id, "skiros:contain", world.cube.id, False)  # what a move would do
    assert inside.revert(ph, world) and not inside.evaluate(ph, world)
    assert world.has_relation(world.table.id, "skiros:contain", world.cube.id)  # the old one is back
    assert not inside.setTrue(params(world, None, world.cube.id), world)  # an abstract end: cannot


def test_setTrue_and_revert_properties(world):
    ph = params(world, world.cube.id, kind=ParamTypes.Required)
    idle = ConditionProperty("Idle", "skiros:StateProperty", "Subject", "=", "Idle", True)
    assert not idle.evaluate(ph, world)
    assert idle.setTrue(ph, world) and idle.evaluate(ph, world)
    assert idle.revert(ph, world) and not idle.evaluate(ph, world)
    assert not world.get_element(world.cube.id).hasProperty("skiros:StateProperty")

    no_size = ConditionHasProperty("NoSize", "skiros:Size", "Subject", False)
    assert no_size.setTrue(ph, world) and no_size.evaluate(ph, world)
    assert no_size.revert(ph, world) and world.get_element(world.cube.id).getProperty("skiros:Size").value == 0.05

    busy = ConditionProperty("Busy", "skiros:Size", "Subject", "=", 0.05, False)  # removes the value
    assert busy.setTrue(ph, world) and world.get_element(world.cube.id).getProperty("skiros:Size").values == []
    assert busy.revert(ph, world) and world.get_element(world.cube.id).getProperty("skiros:Size").values == [0.05]


def test_setTrue_and_revert_specified_and_generated(world):
    ph = params(world, kind=ParamTypes.Required)
    made = ConditionGenerate("Made", "Subject", True)
    assert made.setTrue(ph, world)
    new = ph.getParamValue("Subject")
    assert not new.isAbstract() and new.label == "==FAKE==" and world.has_element(new.id)
    assert made.revert(ph, world) and ph.getParamValue("Subject").isAbstract() and not world.has_element(new.id)

    ph = params(world, world.cube.id, kind=ParamTypes.Required)
    consumed = ConditionGenerate("Consume", "Subject", False)
    assert consumed.setTrue(ph, world) and not world.has_element(world.cube.id)
    assert consumed.revert(ph, world) and world.has_element(world.cube.id)

    given = ConditionIsSpecified("Given", "Subject", False)
    assert given.setTrue(ph, world) and ph.getParamValue("Subject").isAbstract()
    assert given.revert(ph, world) and ph.getParamValue("Subject").id == world.cube.id


# ---- setDesiredState: what grounding looks for ---------------------------------------------------
def test_setDesiredState_marks_the_abstract_elements():
    ph = ParamHandler()
    ph.addParam("Gripper", Element("skiros:Gripper", "", "skiros:Gripper-7"), ParamTypes.Required)
    ph.addParam("Object", Element("skiros:Thing"), ParamTypes.Required)
    ConditionRelation("Holds", "skiros:contain", "Gripper", "Object", True).setDesiredState(ph)
    ConditionProperty("Idle", "skiros:StateProperty", "Object", "=", "Idle", True).setDesiredState(ph)
    ConditionHasProperty("Sized", "skiros:Size", "Object", True).setDesiredState(ph)
    ConditionOnType("IsCube", "Object", "skiros:Cube").setDesiredState(ph)
    AbstractConditionRelation("May", "skiros:contain", "Gripper", "Object", True).setDesiredState(ph)
    o = ph.getParamValue("Object")
    assert o.getRelations() == [  # the other end named by its parameter key
        {"src": "Gripper", "type": "skiros:contain", "dst": "-1", "state": True, "abstract": False},
        {"src": "Gripper", "type": "skiros:contain", "dst": "-1", "state": True, "abstract": True}]
    assert o.hasProperty("skiros:StateProperty", "Idle") and o.hasProperty("skiros:Size") and o.type == "skiros:Cube"
    assert ph.getParamValue("Gripper").getRelations() == []  # a concrete element is left alone


# ---- the rest of the API -------------------------------------------------------------------------
def test_equality_conflicts_keys_and_remap():
    a = ConditionRelation("A", "skiros:contain", "Gripper", "Object", True)
    assert a == ConditionRelation("other label", "skiros:contain", "Gripper", "Object", True)
    assert a != AbstractConditionRelation("A", "skiros:contain", "Gripper", "Object", True)
    assert a.hasConflict(ConditionRelation("B", "skiros:contain", "Gripper", "Object", False))
    assert not a.hasConflict(ConditionRelation("B", "skiros:contain", "Gripper", "Thing", False))
    assert ConditionIsSpecified("x", "K", True).hasConflict(ConditionIsSpecified("y", "K", False))
    assert a.getKeys() == ["Gripper", "Object"] and a._subject_key == "Gripper" and a._owl_label == "skiros:contain"
    a.remap("Object", "Target")
    assert a.getKeys() == ["Gripper", "Target"] and a.getDescription() == "[A] Gripper-skiros:contain-Target (True)"
    either = ConditionOr(True)
    assert either.getKeys() == [] and either.label == "or"
    either.addCondition(a)
    either.addCondition(ConditionIsSpecified("S", "Speed", True))
    assert either.getKeys() == ["Gripper", "Target", "Speed"] and either.label == "A or S"
    assert either == ConditionOr(a, ConditionIsSpecified("S", "Speed", True)) and not either.hasConflict(either)


def test_getParamId_needs_parameters_first():
    c = ConditionIsSpecified("x", "K", True)
    with pytest.raises(RuntimeError, match="before evaluate"):
        c.getParamId("K")
    ph = ParamHandler()
    ph.addParam("K", Element("skiros:Cube", "", "skiros:Cube-1"), ParamTypes.Required)
    c.evaluate(ph)
    assert c.getParamId("K") == "skiros:Cube-1"


def test_toElement():
    e = ConditionProperty("Idle", "skiros:StateProperty", "Gripper", "=", "Idle", True).toElement()
    assert (e.type, e.label) == ("skiros:ConditionProperty", "Idle")
    assert {p.key: p.value for p in e.properties} == {
        "skiros:hasSubject": "Gripper", "skiros:appliedOnType": "skiros:StateProperty", "skiros:operator": "=",
        "skiros:desiredValue": "Idle", "skiros:desiredState": True}
    e = AbstractConditionRelation("May", "skiros:contain", "A", "B", False).toElement()
    assert e.type == "skiros:AbstractConditionRelation" and e.getProperty("skiros:hasObject").value == "B"
    assert ConditionOnType("T", "A", "skiros:Cube").toElement().getProperty("skiros:desiredValue").value == "skiros:Cube"
    assert ConditionOr(False).toElement().getProperty("skiros:desiredState").value is False


def test_or_conditions_go_to_the_manager_with_labels_of_their_own():
    first = ConditionOr(True)
    first.addCondition(ConditionIsSpecified("a", "A", True))
    second = ConditionOr(True)
    second.addCondition(ConditionIsSpecified("b", "B", True))
    first.label = second.label = "or"  # as SkiROS2 names them all
    msgs = condition_msgs([first, second])
    assert [m.or_label for m in msgs] == ["a", "b"]  # (unnamed: named by the members)
    first.label, second.label = "either", "either"
    assert [m.or_label for m in condition_msgs([first, second])] == ["either", "either (2)"]
    with pytest.raises(ValueError, match="no conditions"):
        condition_msgs([ConditionOr(True)])
    with pytest.raises(ValueError, match="desired_state False"):
        condition_msgs([ConditionOr(False, ConditionIsSpecified("a", "A"))])


def test_param_options_add_skiros2s_conditions():
    class Use(SkillDescription):
        def createDescription(self):
            self.addParam("Tool", Element("skiros:Gripper"), ParamTypes.Required,
                          [ParamOptions.Lock, ParamOptions.RespectType, ParamOptions.Consume])
            self.addParam("Part", Element("skiros:Product"), ParamTypes.Optional, [ParamOptions.Unspecify])
            self.addParam("Mode", "open", ParamTypes.Required, ["open", "close"])  # allowed values, as before

    d = Use()
    assert [c.label for c in d.preConditions] == ["ToolIdle", "ToolOfType"]
    assert [c.label for c in d.holdConditions] == ["ToolBusy"]
    assert [c.label for c in d.postConditions] == ["ToolIdle", "ConsumeTool", "UnsetPart"]
    assert d.preConditions[1].owl == "skiros:Gripper" and d.holdConditions[0].desired_state is False
    assert d.params["Tool"].options == [] and d.params["Mode"].options == ["open", "close"]
