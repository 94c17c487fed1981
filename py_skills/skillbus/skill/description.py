"""SkillDescription: what a skill is (parameters and conditions), separate from how it is
done, as in SkiROS2. Subclass it and fill ``createDescription``::

    class Pick(SkillDescription):
        def createDescription(self):
            self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
            self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Inferred)
            self.addPreCondition(self.getRelationCond("Holding", "skiros:contain", "Gripper", "Object", False))
            self.addPostCondition(self.getRelationCond("Holds", "skiros:contain", "Gripper", "Object", True))
"""

from __future__ import annotations

from typing import Any

from skillbus.skill.conditions import (ConditionAbstractRelation, ConditionBase, ConditionGenerate,
                                       ConditionHasProperty, ConditionIsSpecified, ConditionOnType,
                                       ConditionProperty, ConditionRelation)
from skillbus.skill.params import ParamHandler, ParamTypes
from skillbus.world.element import Element

ROBOT_CONCEPT = "skiros:Agent"


class SkillDescription:
    def __init__(self) -> None:
        self._params = ParamHandler()
        self._pre_conditions: list[ConditionBase] = []
        self._hold_conditions: list[ConditionBase] = []
        self._post_conditions: list[ConditionBase] = []
        self.createDescription()
        if not self._params.hasParam("Robot"):
            # Every skill runs on some robot: an agent element, inferred (SkiROS2 does the same).
            self.addParam("Robot", Element(ROBOT_CONCEPT), ParamTypes.Inferred)
        self._check()

    def createDescription(self) -> None:
        """Override: addParam and add*Condition calls."""

    # -- building ----------------------------------------------------------------
    @property
    def type(self) -> str:
        return type(self).__name__

    @property
    def params(self) -> ParamHandler:
        return self._params

    def addParam(self, key: str, value: Any, param_type: ParamTypes, options: list | None = None,
                 description: str = "") -> None:
        self._params.addParam(key, value, param_type, options, description)

    def addPreCondition(self, condition: ConditionBase) -> None:
        self._pre_conditions.append(self._condition(condition))

    def addHoldCondition(self, condition: ConditionBase) -> None:
        self._hold_conditions.append(self._condition(condition))

    def addPostCondition(self, condition: ConditionBase) -> None:
        self._post_conditions.append(self._condition(condition))

    @staticmethod
    def _condition(c: Any) -> ConditionBase:
        if not isinstance(c, ConditionBase):
            raise TypeError(f"a condition is expected, got {type(c).__name__}")
        return c

    @property
    def preConditions(self) -> list[ConditionBase]:
        return self._pre_conditions

    @property
    def holdConditions(self) -> list[ConditionBase]:
        return self._hold_conditions

    @property
    def postConditions(self) -> list[ConditionBase]:
        return self._post_conditions

    def plannable(self) -> bool:
        """A planner can use a skill only if it says what it needs and what it does."""
        return bool(self._pre_conditions) and bool(self._post_conditions)

    def _check(self) -> None:
        """Every condition must name parameters the skill has."""
        for c in self._pre_conditions + self._hold_conditions + self._post_conditions:
            for key in c.keys():
                if not self._params.hasParam(key):
                    raise ValueError(f"{self.type}: condition {c.label} uses parameter {key!r}, which the "
                                     f"skill does not declare (declared: {', '.join(self._params)})")

    # -- SkiROS2's condition helpers (same arguments as the classes, label first) ---------
    def getRelationCond(self, label, relation, subject_param, object_param, desired_state=True):
        return ConditionRelation(label, relation, subject_param, object_param, desired_state)

    def getAbstractRelationCond(self, label, relation, subject_param, object_param, desired_state=True):
        return ConditionAbstractRelation(label, relation, subject_param, object_param, desired_state)

    def getPropCond(self, label, property, subject_param, operator, value, desired_state=True):
        return ConditionProperty(label, property, subject_param, operator, value, desired_state)

    def getHasPropCond(self, label, property, subject_param, desired_state=True):
        return ConditionHasProperty(label, property, subject_param, desired_state)

    def getIsSpecifiedCond(self, label, subject_param, desired_state=True):
        return ConditionIsSpecified(label, subject_param, desired_state)

    def getGenerateCond(self, label, subject_param, desired_state=True):
        return ConditionGenerate(label, subject_param, desired_state)

    def getOnTypeCond(self, label, subject_param, type):
        return ConditionOnType(label, subject_param, type)
