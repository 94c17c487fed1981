"""Conditions on parameters and the world model, with SkiROS2's classes, signatures and
methods (skiros2_common.core.conditions). Each takes a label first and ``desired_state``
last. The skill manager checks them against the world model: pre-conditions when a skill
starts, hold-conditions on every tick, post-conditions when it ends; a planner reads them
as what a skill needs and does.

    >>> c = ConditionRelation("InGripper", "skiros:contain", "Gripper", "Object", True)
    >>> c.label, c.subject_key, c.owl, c.object_key
    ('InGripper', 'Gripper', 'skiros:contain', 'Object')
    >>> c.getDescription()
    '[InGripper] Gripper-skiros:contain-Object (True)'

``evaluate(ph, wmi)`` says whether a condition holds as desired for the parameters `ph`:

* with a world model (`wmi`, e.g. skillbus.world.WorldModelInterface) it judges as the
  skill manager does (skillbus.skill.condition_check): on the world's copies of the
  elements, and a condition that cannot be judged fails;
* without one (``wmi=None``, as SkiROS2's unit tests call it) it judges the elements in
  the parameters as SkiROS2 does: Property and HasProperty read the parameter's element
  (an abstract one too), IsSpecified and Generate ask whether it is concrete. What needs
  the world (Relation, AbstractRelation, OnType but for an exact type) fails.

``setTrue(ph, wmi)`` / ``revert(ph, wmi)`` make a condition true in the world model and
undo it (SkiROS2's simulation); ``setDesiredState(ph)`` writes it into the abstract
elements of the parameters (what grounding then looks for).
"""

from __future__ import annotations

import copy
import operator
from typing import Any

from skillbus.skill import condition_check
from skillbus.skill.param import ParamTypes
from skillbus.world.element import Element

OPERATORS = ("=", "!=", ">", ">=", "<", "<=")
_ORDER = {">": operator.gt, ">=": operator.ge, "<": operator.lt, "<=": operator.le}
FAKE_LABEL = "==FAKE=="  # SkiROS2's label for an element a simulated ConditionGenerate makes up


def _alias(name: str, doc: str = "") -> property:
    """SkiROS2's name for an attribute (its code and skills read ``c._subject_key``)."""
    return property(lambda self: getattr(self, name), lambda self, v: setattr(self, name, v), doc=doc)


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
        self._params: Any = None  # what the last evaluate / setTrue / revert was given
        self._wm: Any = None
        self._has_cache, self._cache = False, None
        self._description = ""

    _label = _alias("label")
    _subject_key = _alias("subject_key")
    _object_key = _alias("object_key")
    _desired_state = _alias("desired_state")
    _owl_label = _alias("owl")
    _operator = _alias("operator")
    _value = _alias("value")

    # -- what it is about --------------------------------------------------------------
    def keys(self) -> list[str]:
        """The parameters the condition reads."""
        return [k for k in (self.subject_key, self.object_key) if k]

    def getKeys(self) -> list[str]:
        return self.keys()

    def getDescription(self) -> str:
        return self._description

    def _setDescription(self) -> None:
        self._description = f"[{self.label}] {self.subject_key} ({self.desired_state})"

    def remap(self, initial_key: str, target_key: str) -> None:
        """Renames a parameter the condition reads."""
        if self.subject_key == initial_key:
            self.subject_key = target_key
        if self.object_key == initial_key:
            self.object_key = target_key
        self._setDescription()

    def getParamId(self, key: str) -> str | None:
        """The id of the element in parameter `key` of the handler last evaluated."""
        if self._params is None:
            raise RuntimeError(f"{self.label}: getParamId before evaluate / setTrue (no parameters yet)")
        e = self._params.getParamValue(key)
        return e.id if isinstance(e, Element) else None

    def describe(self) -> dict:
        return {"kind": self.kind, "label": self.label, "subject": self.subject_key, "object": self.object_key,
                "owl": self.owl, "operator": self.operator, "value": self.value,
                "desired_state": self.desired_state}

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.label})"

    # -- comparing --------------------------------------------------------------------------
    def isEqual(self, other: Any) -> bool:
        return type(other) is type(self) and self._fields() == other._fields()

    def _fields(self) -> tuple:
        return (self.subject_key, self.object_key, self.owl, self.operator, self.value, self.desired_state)

    def __eq__(self, other: object) -> bool:
        return self.isEqual(other)

    def __ne__(self, other: object) -> bool:
        return not self.isEqual(other)

    __hash__ = None  # type: ignore[assignment]  # compared by content, as in SkiROS2

    def hasConflict(self, other: Any) -> bool:
        """Whether both cannot hold at once: the same statement on the same parameters
        (or the same elements) with opposite desired states."""
        return (type(other) is type(self) and self.owl == other.owl and self.value == other.value
                and self.desired_state != other.desired_state and self._same_elements(other))

    def _same_elements(self, other: "ConditionBase") -> bool:
        same_keys = self.keys() == other.keys()
        if self._params is None or other._params is None:
            return same_keys
        ids = [self.getParamId(k) for k in self.keys()]
        return same_keys or (None not in ids and ids == [other.getParamId(k) for k in other.keys()])

    # -- judging and simulating --------------------------------------------------------------
    def evaluate(self, ph: Any, wmi: Any = None) -> bool:
        """Whether the condition holds as desired (see the module's docstring)."""
        self._params, self._wm = ph, wmi
        if wmi is None:
            return self._on_params(ph)
        return condition_check.satisfied(self, ph, wmi)

    def _on_params(self, ph: Any) -> bool:
        """SkiROS2's judgement without a world model (default: cannot judge)."""
        return False

    def setTrue(self, ph: Any, wmi: Any) -> bool:
        """Makes the condition hold in the world model (and the parameters); False when
        it cannot."""
        return False

    def revert(self, ph: Any, wmi: Any) -> bool:
        """Undoes the last setTrue; False when there is nothing to undo."""
        return False

    def setDesiredState(self, ph: Any) -> None:
        """Writes the desired state into the abstract elements of `ph`."""

    def toElement(self) -> Element:
        """The condition as SkiROS2 describes it in the world model."""
        e = Element("skiros:" + self.owl_class(), self.label)
        e.setProperty("skiros:hasSubject", self.subject_key)
        return e

    @classmethod
    def owl_class(cls) -> str:
        return cls.__name__

    # -- helpers -------------------------------------------------------------------------------
    def _element(self, ph: Any, key: str) -> Element | None:
        v = ph.getParamValue(key) if key and ph.hasParam(key) else None
        return v if isinstance(v, Element) else None

    def _concrete(self, ph: Any, key: str) -> Element | None:
        e = self._element(ph, key)
        return e if e is not None and not e.isAbstract() else None

    def _restore(self, ph: Any, wmi: Any) -> bool:
        """revert for a condition whose setTrue changed the subject's properties: writes
        the cached element's properties back (those setTrue added are removed)."""
        if not self._has_cache:
            return False
        self._params, self._wm = ph, wmi
        saved: Element = self._cache
        ph.specify(self.subject_key, saved)
        # The cache remembers what was loaded before setTrue wrote: updating from it would
        # write nothing. Start from the world's element as it is now and put the saved
        # properties on it, so the update writes exactly the difference.
        now = wmi.get_element(saved.id) if wmi.has_element(saved.id) else copy.deepcopy(saved)
        for key in list(now.available_properties):
            now.removeProperty(key)
        for p in saved.properties:
            now.setProperty(p.key, list(p.values))
        wmi.update_element(now)
        self._has_cache = False
        return True


class _PropertyCondition(ConditionBase):
    """A condition about the subject element's properties: made true by editing the
    element (_edit, per condition), written to the world model and undone from a copy."""

    def _edit(self, e: Element) -> None:
        raise NotImplementedError

    def setTrue(self, ph: Any, wmi: Any) -> bool:
        self._params, self._wm = ph, wmi
        e = self._concrete(ph, self.subject_key)
        if e is None:
            return False
        self._has_cache, self._cache = True, copy.deepcopy(e)
        self._edit(e)
        ph.specify(self.subject_key, e)
        wmi.update_element(e)
        return True

    def revert(self, ph: Any, wmi: Any) -> bool:
        return self._restore(ph, wmi)

    def setDesiredState(self, ph: Any) -> None:
        e = self._element(ph, self.subject_key)
        if e is not None and e.isAbstract():
            self._edit(e)


class ConditionHasProperty(_PropertyCondition):
    """The element in `subject_param` has `property` (with any value)."""
    kind = "HasProperty"

    def __init__(self, label: str, property: str, subject_param: str, desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)
        self.owl = property
        self._setDescription()

    def _setDescription(self) -> None:
        self._description = f"[{self.label}] {self.subject_key}-{self.owl} ({self.desired_state})"

    def _on_params(self, ph: Any) -> bool:
        e = self._element(ph, self.subject_key)
        if e is None:
            return False
        if e.isAbstract():  # SkiROS2: an optional parameter need not have it; a required one cannot be judged
            return ph.getParam(self.subject_key).paramType == ParamTypes.Optional
        return e.hasProperty(self.owl, not_none=True) == self.desired_state

    def _edit(self, e: Element) -> None:
        # setTrue adds the property (desired) or removes it (not desired)
        if self.desired_state and not e.hasProperty(self.owl):
            e.setProperty(self.owl, "")
        elif not self.desired_state and e.hasProperty(self.owl):
            e.removeProperty(self.owl)

    def toElement(self) -> Element:
        e = super().toElement()
        e.setProperty("skiros:appliedOnType", self.owl)
        e.setProperty("skiros:desiredState", self.desired_state)
        return e


class ConditionProperty(_PropertyCondition):
    """`property` of the element in `subject_param` compares to `value` with `operator`
    (one of =, !=, >, >=, <, <=; SkiROS2 has no !=)."""
    kind = "Property"

    def __init__(self, label: str, property: str, subject_param: str, operator: str, value: Any,
                 desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)
        if operator not in OPERATORS:
            raise ValueError(f"{label}: operator {operator!r} is not one of {', '.join(OPERATORS)}")
        self.owl, self.operator, self.value = property, operator, value
        self._setDescription()

    def _setDescription(self) -> None:
        self._description = (f"[{self.label}] {self.subject_key}-{self.owl}-{self.operator}{self.value} "
                             f"({self.desired_state})")

    def _on_params(self, ph: Any) -> bool:
        # SkiROS2: "=" asks whether the value is among the property's values; the other
        # operators compare the first value, and fail (whatever the desired state) when
        # the property is missing or the values do not compare.
        e = self._element(ph, self.subject_key)
        if e is None:
            return False
        if self.operator in ("=", "!="):
            among = e.hasProperty(self.owl, self.value)
            return (among if self.operator == "=" else not among) == self.desired_state
        if not e.hasProperty(self.owl, not_none=True):
            return False
        try:
            return bool(_ORDER[self.operator](e.getProperty(self.owl).value, self.value)) == self.desired_state
        except TypeError:
            return False

    def _edit(self, e: Element) -> None:
        # setTrue adds the value to the property (desired) or removes it (not desired); as in
        # SkiROS2 this is exact for "=" only
        if self.desired_state:
            if not e.hasProperty(self.owl, self.value):
                e.appendProperty(self.owl, self.value)
        else:
            while e.hasProperty(self.owl, self.value):
                e.getProperty(self.owl).removeValue(self.value)

    def toElement(self) -> Element:
        e = super().toElement()
        e.setProperty("skiros:appliedOnType", self.owl)
        e.setProperty("skiros:operator", self.operator)
        e.setProperty("skiros:desiredValue", self.value)
        e.setProperty("skiros:desiredState", self.desired_state)
        return e


class _ElementPairCondition(ConditionBase):
    """A relation `relation` between the elements of `subject_param` and `object_param`."""

    def __init__(self, label: str, relation: str, subject_param: str, object_param: str,
                 desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)
        self.owl, self.object_key = relation, object_param
        self._setDescription()

    def _setDescription(self) -> None:
        self._description = (f"[{self.label}] {self.subject_key}-{self.owl}-{self.object_key} "
                             f"({self.desired_state})")

    def getKeys(self) -> list[str]:
        return [self.subject_key, self.object_key]

    def _mark(self, e: Element, subj: str, obj: str, abstract: bool) -> None:
        if not e.hasRelation(subj, self.owl, obj, self.desired_state, abstract):
            e.addRelation(subj, self.owl, obj, self.desired_state, abstract)

    def toElement(self) -> Element:
        e = super().toElement()
        e.setProperty("skiros:hasObject", self.object_key)
        e.setProperty("skiros:appliedOnType", self.owl)
        e.setProperty("skiros:desiredState", self.desired_state)
        return e


class ConditionRelation(_ElementPairCondition):
    """The elements in `subject_param` and `object_param` are related by `relation` (or
    a subproperty of it)."""
    kind = "Relation"

    def setTrue(self, ph: Any, wmi: Any) -> bool:
        """Sets (desired) or removes the relation in the world model, remembering the
        object's incoming relations for revert."""
        self._params, self._wm = ph, wmi
        s, o = self._concrete(ph, self.subject_key), self._concrete(ph, self.object_key)
        if s is None or o is None:
            return False
        self._has_cache, self._cache = True, wmi.get_relations("", "", o.id)
        return wmi.set_relation(s.id, self.owl, o.id, self.desired_state) is not False

    def revert(self, ph: Any, wmi: Any) -> bool:
        if not self._has_cache:
            return False
        self._params, self._wm = ph, wmi
        s, o = self._element(ph, self.subject_key), self._element(ph, self.object_key)
        if s is not None and o is not None:
            wmi.set_relation(s.id, self.owl, o.id, not self.desired_state)
        for r in self._cache:
            wmi.set_relation(r["src"], r["type"], r["dst"], True)
        self._has_cache = False
        return True

    def setDesiredState(self, ph: Any) -> None:
        """Puts the relation on the abstract one of the two elements, naming the other by
        its parameter key (grounding couples the two parameters through it)."""
        s, o = self._element(ph, self.subject_key), self._element(ph, self.object_key)
        if s is not None and s.isAbstract():
            self._mark(s, "-1", self.object_key, abstract=False)
        elif o is not None and o.isAbstract():
            self._mark(o, self.subject_key, "-1", abstract=False)


class AbstractConditionRelation(_ElementPairCondition):
    """As ConditionRelation, at the level of concepts: the ontology allows a `relation`
    between the concepts of the two elements."""
    kind = "AbstractRelation"

    def setDesiredState(self, ph: Any) -> None:
        s, o = self._element(ph, self.subject_key), self._element(ph, self.object_key)
        if s is not None and s.isAbstract():
            self._mark(s, "-1", self.object_key, abstract=True)
        if o is not None and o.isAbstract():
            self._mark(o, self.subject_key, "-1", abstract=True)


ConditionAbstractRelation = AbstractConditionRelation  # skillbus's earlier name


class ConditionIsSpecified(ConditionBase):
    """The parameter `subject_param` has a value (an element parameter: a concrete element)."""
    kind = "IsSpecified"

    def __init__(self, label: str, subject_param: str, desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)
        self._setDescription()

    def _on_params(self, ph: Any) -> bool:
        return condition_check.judged(self, ph, None)  # about the parameter alone: the same with a world

    def setTrue(self, ph: Any, wmi: Any) -> bool:
        """Makes up a concrete element (desired) or forgets the id (not desired), in the
        parameters only."""
        self._params, self._wm = ph, wmi
        e = self._element(ph, self.subject_key)
        self._has_cache, self._cache = True, copy.deepcopy(ph.getParamValue(self.subject_key))
        if e is not None and e.isAbstract() and self.desired_state:
            ph.specify(self.subject_key, Element(e.type, FAKE_LABEL))
        elif e is not None and not e.isAbstract() and not self.desired_state:
            e._id = ""
            ph.specify(self.subject_key, e)
        return True

    def revert(self, ph: Any, wmi: Any) -> bool:
        if not self._has_cache:
            return False
        self._params, self._wm = ph, wmi
        ph.specify(self.subject_key, self._cache)
        self._has_cache = False
        return True

    def hasConflict(self, other: Any) -> bool:
        return (type(other) is type(self) and self.subject_key == other.subject_key
                and self.desired_state != other.desired_state)

    def toElement(self) -> Element:
        e = super().toElement()
        e.setProperty("skiros:desiredState", self.desired_state)
        return e


class ConditionGenerate(ConditionIsSpecified):
    """The skill generates (creates in the world model) the element of `subject_param`;
    judged as ConditionIsSpecified."""
    kind = "Generate"

    def setTrue(self, ph: Any, wmi: Any) -> bool:
        """Adds a made-up element to the world model (desired) or removes the element
        (not desired)."""
        self._params, self._wm = ph, wmi
        e = self._element(ph, self.subject_key)
        self._has_cache, self._cache = True, copy.deepcopy(e)
        if e is not None and e.isAbstract() and self.desired_state:
            made = Element(e.type, FAKE_LABEL)
            added = wmi.add_element(made)
            ph.specify(self.subject_key, added if isinstance(added, Element) else made)
        elif e is not None and not e.isAbstract() and not self.desired_state:
            wmi.remove_element(e.id)
            e._id = ""
            ph.specify(self.subject_key, e)
        return True

    def revert(self, ph: Any, wmi: Any) -> bool:
        if not self._has_cache:
            return False
        self._params, self._wm = ph, wmi
        before: Element | None = self._cache
        now = self._element(ph, self.subject_key)
        if before is not None and now is not None:
            if before.isAbstract() and not now.isAbstract():
                wmi.remove_element(now.id)
            elif not before.isAbstract() and now.isAbstract():
                wmi.add_element(copy.deepcopy(before))  # with its id: the world model keeps it
        ph.specify(self.subject_key, before)
        self._has_cache = False
        return True


class ConditionOnType(ConditionBase):
    """The element in `subject_param` is of concept `type` (or a subclass). SkiROS2's has
    no desired state; it is True here unless given."""
    kind = "OnType"

    def __init__(self, label: str, subject_param: str, type: str, desired_state: bool = True) -> None:
        super().__init__(label, subject_param, desired_state)
        self.owl = type
        self._setDescription()

    _value = _alias("owl", "SkiROS2 keeps the type as the condition's value")

    def _setDescription(self) -> None:
        self._description = f"[{self.label}] {self.subject_key} is of type {self.owl}"

    def _on_params(self, ph: Any) -> bool:
        # Without the ontology only the exact type can be told.
        e = self._element(ph, self.subject_key)
        return e is not None and e.type == self.owl and self.desired_state

    def setTrue(self, ph: Any, wmi: Any) -> bool:
        return True

    def revert(self, ph: Any, wmi: Any) -> bool:
        return True

    def setDesiredState(self, ph: Any) -> None:
        e = self._element(ph, self.subject_key)
        if e is not None and e.isAbstract():
            e.type = self.owl

    def hasConflict(self, other: Any) -> bool:
        """Two types asked of one parameter (SkiROS2: any two OnType conditions on it)."""
        return type(other) is type(self) and self.subject_key == other.subject_key and self.owl != other.owl

    def toElement(self) -> Element:
        e = super().toElement()
        e.setProperty("skiros:desiredValue", self.owl)
        return e


class ConditionOr(ConditionBase):
    """True when any of its conditions is. Built either way:
    ``ConditionOr(c1, c2, ...)`` or, as in SkiROS2, ``ConditionOr(True)`` and then
    ``addCondition(c)`` for each (``desired_state`` False: true when none is)."""
    kind = "Or"

    def __init__(self, *conditions: Any, desired_state: bool = True, label: str = "") -> None:
        if conditions and isinstance(conditions[0], bool):  # SkiROS2: ConditionOr(desired_state)
            desired_state, conditions = conditions[0], conditions[1:]
        super().__init__("or", "", desired_state)
        self._label_given = label
        self.conditions: list[ConditionBase] = []
        for c in conditions:
            for x in (c if isinstance(c, (list, tuple)) else [c]):
                self.addCondition(x)
        self._setDescription()

    _children = _alias("conditions")

    @property
    def label(self) -> str:  # type: ignore[override]
        return self._label_given or " or ".join(c.label for c in self.conditions) or "or"

    @label.setter
    def label(self, value: str) -> None:
        self._label_given = "" if value == "or" else value

    def addCondition(self, condition: ConditionBase) -> None:
        if not isinstance(condition, ConditionBase):
            raise ValueError(f"ConditionOr takes conditions, got {condition!r}")
        self.conditions.append(condition)
        self._setDescription()

    def _setDescription(self) -> None:
        self._description = "[or] ( " + "".join(f" {c.getDescription()} " for c in self.conditions) + ")"

    def keys(self) -> list[str]:
        return [k for c in self.conditions for k in c.keys()]

    def getKeys(self) -> list[str]:
        return [k for c in self.conditions for k in c.getKeys()]

    def remap(self, initial_key: str, target_key: str) -> None:
        for c in self.conditions:
            c.remap(initial_key, target_key)
        self._setDescription()

    def evaluate(self, ph: Any, wmi: Any = None) -> bool:
        self._params, self._wm = ph, wmi
        if wmi is None:
            any_holds = any(c.evaluate(ph, None) for c in self.conditions)
        else:  # as the manager: the members are judged (no optional-parameter pass)
            any_holds = any(c.evaluate(ph, wmi) if isinstance(c, ConditionOr) else condition_check.judged(c, ph, wmi)
                            for c in self.conditions)
        return any_holds == self.desired_state

    def setTrue(self, ph: Any, wmi: Any) -> bool:
        self._params, self._wm = ph, wmi
        return all(c.setTrue(ph, wmi) for c in self.conditions)

    def revert(self, ph: Any, wmi: Any) -> bool:
        self._params, self._wm = ph, wmi
        return all(c.revert(ph, wmi) for c in self.conditions)

    def setDesiredState(self, ph: Any) -> None:
        for c in self.conditions:
            c.setDesiredState(ph)

    def isEqual(self, other: Any) -> bool:
        return (type(other) is type(self) and self.desired_state == other.desired_state
                and len(self.conditions) == len(other.conditions)
                and all(a.isEqual(b) for a, b in zip(self.conditions, other.conditions)))

    def hasConflict(self, other: Any) -> bool:
        """A disjunction rules nothing out on its own (SkiROS2 raises "TODO" here)."""
        return False

    def toElement(self) -> Element:
        e = Element("skiros:ConditionOr", self.label)
        e.setProperty("skiros:desiredState", self.desired_state)
        return e

    def describe(self) -> dict:
        d = super().describe()
        d["conditions"] = [c.describe() for c in self.conditions]
        return d
