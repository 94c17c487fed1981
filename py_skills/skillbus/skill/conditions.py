"""Conditions on parameters and the world model, with SkiROS2's classes and signatures.
Each takes a label first and ``desired_state`` last. The skill manager checks them
against the world model: pre-conditions when a skill starts, hold-conditions on every
tick, post-conditions when it ends; a planner reads them as what a skill needs and does.

    >>> c = ConditionRelation("InGripper", "skiros:contain", "Gripper", "Object", True)
    >>> c.label, c.subject_key, c.owl, c.object_key
    ('InGripper', 'Gripper', 'skiros:contain', 'Object')
"""

from __future__ import annotations

from typing import Any

OPERATORS = ("=", "!=", ">", ">=", "<", "<=")


class ConditionBase:
    kind = ""

    def __init__(self, label: str, subject_key: str, desired_state: bool = True) -> None:
        if not isinstance(label, str) or not label:
            raise ValueError(f"{type(self).__name__}: the label comes first and must be a non-empty string")
        self.label, self.subject_key, self.desired_state = label, subject_key, bool(desired_state)
        self.owl = ""          # property, relation or concept the condition is about
        self.object_key = ""
        self.operator = ""
        self.value: Any = None

    def keys(self) -> list[str]:
        """The parameters the condition reads."""
        return [k for k in (self.subject_key, self.object_key) if k]

    def describe(self) -> dict:
        return {"kind": self.kind, "label": self.label, "subject": self.subject_key, "object": self.object_key,
                "owl": self.owl, "operator": self.operator, "value": self.value,
                "desired_state": self.desired_state}

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.label})"


class ConditionHasProperty(ConditionBase):
    """The element in `subject_param` has `property` (with any value)."""
    kind = "HasProperty"

    def __init__(self, label: str, property: str, subject_param: str, desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)
        self.owl = property


class ConditionProperty(ConditionBase):
    """`property` of the element in `subject_param` compares to `value` with `operator`."""
    kind = "Property"

    def __init__(self, label: str, property: str, subject_param: str, operator: str, value: Any,
                 desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)
        if operator not in OPERATORS:
            raise ValueError(f"{label}: operator {operator!r} is not one of {', '.join(OPERATORS)}")
        self.owl, self.operator, self.value = property, operator, value


class ConditionRelation(ConditionBase):
    """The elements in `subject_param` and `object_param` are related by `relation`."""
    kind = "Relation"

    def __init__(self, label: str, relation: str, subject_param: str, object_param: str,
                 desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)
        self.owl, self.object_key = relation, object_param


class ConditionAbstractRelation(ConditionRelation):
    """As ConditionRelation, at the level of concepts (the ontology), not instances."""
    kind = "AbstractRelation"


class ConditionIsSpecified(ConditionBase):
    """The parameter `subject_param` has a value (an element parameter: a concrete element)."""
    kind = "IsSpecified"

    def __init__(self, label: str, subject_param: str, desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)


class ConditionGenerate(ConditionBase):
    """The skill generates (creates in the world model) the element of `subject_param`."""
    kind = "Generate"

    def __init__(self, label: str, subject_param: str, desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)


class ConditionOnType(ConditionBase):
    """The element in `subject_param` is of concept `type` (or a subclass)."""
    kind = "OnType"

    def __init__(self, label: str, subject_param: str, type: str, desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)
        self.owl = type


class ConditionOr(ConditionBase):
    """True when any of its conditions is."""
    kind = "Or"

    def __init__(self, *conditions: ConditionBase | list, label: str = "") -> None:
        flat: list[ConditionBase] = []
        for c in conditions:
            flat.extend(c if isinstance(c, (list, tuple)) else [c])
        if not flat or not all(isinstance(c, ConditionBase) for c in flat):
            raise ValueError("ConditionOr needs one or more conditions")
        super().__init__(label or " or ".join(c.label for c in flat), "", True)
        self.conditions = flat

    def keys(self) -> list[str]:
        return [k for c in self.conditions for k in c.keys()]

    def describe(self) -> dict:
        d = super().describe()
        d["conditions"] = [c.describe() for c in self.conditions]
        return d
