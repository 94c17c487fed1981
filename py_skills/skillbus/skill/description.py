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

import enum
from typing import Any

from skillbus.skill.conditions import (AbstractConditionRelation, ConditionBase, ConditionGenerate,
                                       ConditionHasProperty, ConditionIsSpecified, ConditionOnType, ConditionOr,
                                       ConditionProperty, ConditionRelation)
from skillbus.skill.params import ParamHandler, ParamTypes
from skillbus.world.element import Element

ROBOT_CONCEPT = "sumo:Agent"  # (SkiROS2's: its robots are cora:Robot, skillbus's skiros:Robot, both below it)


class ParamOptions(enum.Enum):
    """Options of an element parameter (SkiROS2's, from its abstract_skill module): each
    adds conditions about the parameter to the description (SkillDescription.addParam).

    Consume:     the skill uses the element up (post: ConditionGenerate, not desired)
    Output:      the skill fills it in (no condition; marks intent)
    Unspecify:   the parameter is left empty (post: ConditionIsSpecified, not desired)
    Lock:        the element must be idle and is busy while the skill runs (pre and post:
                 skiros:StateProperty = "Idle"; hold: not "Idle")
    RespectType: the element must be of the parameter's concept (pre: ConditionOnType)
    """
    Consume = 1
    Output = 2
    Unspecify = 3
    Lock = 4
    RespectType = 5


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
        """Adds a parameter. `options` may hold ParamOptions (SkiROS2's: for an element
        parameter they add conditions) and values the parameter may take (skillbus: shown
        by ``skillbus skills``, not enforced)."""
        options = list(options or [])
        allowed = [o for o in options if not isinstance(o, ParamOptions)]
        self._params.addParam(key, value, param_type, allowed, description)
        if isinstance(value, Element):
            for o in options:
                if isinstance(o, ParamOptions):
                    self._add_option_conditions(key, value, o)

    def _add_option_conditions(self, key: str, value: Element, option: ParamOptions) -> None:
        # The labels are SkiROS2's, so a ported skill's conditions read the same.
        if option == ParamOptions.Consume:
            self._post_conditions.append(ConditionGenerate("Consume" + key, key, False))
        elif option == ParamOptions.Unspecify:
            self._post_conditions.append(ConditionIsSpecified("Unset" + key, key, False))
        elif option == ParamOptions.Lock:
            self._pre_conditions.append(ConditionProperty(key + "Idle", "skiros:StateProperty", key, "=", "Idle", True))
            self._hold_conditions.append(ConditionProperty(key + "Busy", "skiros:StateProperty", key, "=", "Idle",
                                                           False))
            self._post_conditions.append(ConditionProperty(key + "Idle", "skiros:StateProperty", key, "=", "Idle",
                                                           True))
        elif option == ParamOptions.RespectType:
            self._pre_conditions.append(ConditionOnType(key + "OfType", key, value.type))

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
        return AbstractConditionRelation(label, relation, subject_param, object_param, desired_state)

    def getOrCond(self, desired_state=True):
        """An empty ConditionOr: addCondition its members."""
        return ConditionOr(desired_state=desired_state)

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
