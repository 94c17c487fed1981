"""The skill SDK: the code of the skill model's examples works with only its imports
changed (SkiROS2's modules -> skillbus.skill)."""

import pytest

# In SkiROS2 these come from skiros2_skill.core.skill, skiros2_common.core.params,
# skiros2_common.core.world_element, skiros2_common.core.primitive,
# skiros2_common.core.conditions and skiros2_skill.core.processors.
from skillbus.skill import (ConditionIsSpecified, ConditionOr, ConditionProperty, ConditionRelation, Element,
                            Loop, NoFail, ParallelFf, ParamTypes, PrimitiveBase, RetryOnFail, Selector, Sequential,
                            SerialStar, SkillBase, SkillDescription, State)


# ---- the skill model's examples -------------------------------------------------------
class GripperMove(SkillDescription):
    """All parameter kinds."""

    def createDescription(self):
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Inferred)
        self.addParam("Width", float, ParamTypes.Required)                 # typed, must be given
        self.addParam("Mode", "open", ParamTypes.Required, ["open", "close", "grasp"])  # static
        self.addParam("Speed", 0.05, ParamTypes.Optional, description="m/s")           # default
        self.addParam("Force", float, ParamTypes.Optional)                 # may stay empty
        self.addParam("Waypoints", list, ParamTypes.Optional)
        self.addParam("Extra", dict, ParamTypes.Optional)


class Locate(SkillDescription):
    def createDescription(self):
        self.addParam("Camera", Element("skiros:Camera"), ParamTypes.Inferred)
        self.addParam("Container", Element("skiros:Location"), ParamTypes.Required)
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Optional)
        self.addPreCondition(self.getIsSpecifiedCond("HasContainer", "Container", True))
        self.addPreCondition(self.getRelationCond("CameraNotBusy", "skiros:contain", "Camera", "Object", False))
        self.addPostCondition(self.getRelationCond("InContainer", "skiros:contain", "Container", "Object", True))
        self.addPostCondition(self.getIsSpecifiedCond("Found", "Object", True))


class Pick(SkillDescription):
    def createDescription(self):
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Inferred)
        self.addHoldCondition(self.getPropCond("Light", "skiros:Weight", "Object", "<", 2.0, True))
        self.addPostCondition(ConditionRelation("Holds", "skiros:contain", "Gripper", "Object", True))


class gripper_move(PrimitiveBase):
    def createDescription(self):
        self.setDescription(GripperMove(), self.__class__.__name__)

    def onStart(self):
        self.ticks = 0
        return True

    def execute(self):
        self.ticks += 1
        if self.ticks < 3:
            return self.step(f"moving to {self.params['Width'].value}")
        if self.params["Width"].value < 0:
            return self.fail("width must not be negative", -2)
        return self.success("reached")


class pick(SkillBase):
    def createDescription(self):
        self.setDescription(Pick(), self.__class__.__name__)

    def expand(self, skill):
        skill.setProcessor(SerialStar())
        skill(
            self.skill("GripperMove", "", specify={"Mode": "open", "Width": 0.08}),
            self.skill("MoveArm", "", remap={"Target": "Object"}),
            self.skill(ParallelFf())(
                self.skill("GripperMove", "gripper_move", specify={"Mode": "grasp", "Width": 0.0}),
                self.skill("Monitor", ""),
            ),
            self.skill(RetryOnFail(2))(self.skill("Lift", "")),
        )


# ---- tests ----------------------------------------------------------------------------
def test_parameter_kinds():
    d = GripperMove()
    p = d.params
    assert p["Width"].dataType() is float and not p["Width"].isSpecified()
    assert p["Mode"].value == "open" and p["Mode"].hasSpecifiedDefault() and p["Mode"].options == ["open", "close", "grasp"]
    assert p["Speed"].paramType == ParamTypes.Optional and p["Speed"].value == 0.05 and p["Speed"].description == "m/s"
    assert p["Gripper"].dataTypeIs(Element) and not p["Gripper"].isSpecified()  # abstract until grounded
    assert p["Robot"].paramType == ParamTypes.Inferred  # added to every description
    p["Width"].value = 1  # an int where a float is wanted is fine
    with pytest.raises(TypeError, match="parameter Width holds float, not str"):
        p["Width"].value = "wide"
    assert p["Nope"] is None  # SkiROS2: a missing key logs an error (see test_skiros2_params.py)
    p["Waypoints"].value = [1, 2]  # a list-typed parameter holds the list as one value
    assert p["Waypoints"].values == [[1, 2]] and p["Waypoints"].value == [1, 2]


def test_conditions_and_planning():
    loc = Locate()
    assert [c.label for c in loc.preConditions] == ["HasContainer", "CameraNotBusy"]
    assert loc.postConditions[0].describe() == {
        "kind": "Relation", "label": "InContainer", "subject": "Container", "object": "Object",
        "owl": "skiros:contain", "operator": "", "value": None, "desired_state": True}
    assert loc.plannable() and not GripperMove().plannable()
    assert Pick().holdConditions[0].operator == "<"
    assert ConditionOr(ConditionIsSpecified("a", "X"), ConditionIsSpecified("b", "Y")).keys() == ["X", "Y"]


def test_a_condition_on_an_undeclared_parameter_is_named():
    class Broken(SkillDescription):
        def createDescription(self):
            self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
            self.addPreCondition(self.getRelationCond("Oops", "skiros:contain", "Gripper", "Object"))

    with pytest.raises(ValueError, match="Broken: condition Oops uses parameter 'Gripper'"):
        Broken()
    with pytest.raises(ValueError, match="operator '~'"):
        ConditionProperty("x", "skiros:Size", "Object", "~", 1)


def test_primitive_results_set_state_message_and_code():
    g = gripper_move()
    assert g.type == "GripperMove" and g.label == "gripper_move"
    g.params["Width"].value = 0.04
    assert g.onStart()
    assert [g.execute() for _ in range(3)] == [State.Running, State.Running, State.Success]
    assert (g.state, g.message) == (State.Success, "reached")
    g.params["Width"].value = -1.0
    g.onStart()
    g.execute(), g.execute()
    assert g.execute() == State.Failure and (g.message, g.code) == ("width must not be negative", -2)
    with pytest.raises(TypeError, match="code must be an int"):
        g.fail("x", "bad")


def test_compound_expands_to_a_tree_with_processors_remaps_and_specify():
    tree = pick().tree().describe()
    assert tree["type"] == "Pick" and tree["processor"] == "SerialStar"
    kids = tree["children"]
    assert [k["type"] for k in kids] == ["GripperMove", "MoveArm", "", ""]
    assert kids[0]["specify"] == {"Mode": "open", "Width": 0.08}
    assert kids[1]["remap"] == {"Target": "Object"}
    assert kids[2]["processor"] == "ParallelFf" and kids[2]["children"][0]["label"] == "gripper_move"
    assert kids[3]["processor"] == "RetryOnFail(2)"


def test_default_processor_is_serial_star_and_aliases():
    class c(SkillBase):
        def createDescription(self):
            self.setDescription(Pick(), "c")

        def expand(self, skill):
            skill(self.skill("A", ""))

    assert c().tree().describe()["processor"] == "SerialStar"
    assert Sequential().spec() == "SerialStar" and Loop().spec() == "Loop" and NoFail(Selector()).spec() == "NoFail(Selector)"
    with pytest.raises(ValueError):
        Loop(-1)
    with pytest.raises(TypeError, match="must come from self.skill"):
        c().skill("A")("not a node")


def test_a_primitive_must_set_a_description():
    class nothing(PrimitiveBase):
        pass

    with pytest.raises(ValueError, match="must call self.setDescription"):
        nothing()
