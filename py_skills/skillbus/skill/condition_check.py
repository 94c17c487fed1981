"""Judging a condition against a world model the way the skill manager does
(skill_mgr/src/conditions.cpp), so that ``condition.evaluate(ph, wmi)`` in Python and the
manager's check give the same answer on the same world:

* the condition's elements are looked up in the world model by id: their properties
  and relations there count, not the copies in the parameters;
* a condition that cannot be judged (its element is abstract or not in the world, its
  parameter is missing) fails, whatever its desired state: "not holding X" is no answer
  about a missing X;
* a condition about an Optional parameter that has no value (or an abstract element)
  holds without being judged: the skill runs without it; IsSpecified and Generate are
  the way to ask for one. Members of a ConditionOr are always judged;
* Relation: a relation whose predicate is a subproperty of the condition's counts;
  OnType: the element's type or a subclass of it; AbstractRelation: the ontology allows
  the relation between the elements' concepts; Property: the first value compares
  (numbers as numbers, text and booleans for = and != only).

`wmi` needs: has_element, get_element, has_relation, is_instance_of and may_relate
(skillbus.world.WorldModelInterface has them).
"""

from __future__ import annotations

import operator
from typing import Any

from skillbus.skill.param import Param, ParamTypes
from skillbus.world.element import Element

JUDGED_WITHOUT_WORLD = ("IsSpecified", "Generate")  # about the parameter alone

NUMBER_OPERATORS = {"=": operator.eq, "!=": operator.ne, ">": operator.gt, ">=": operator.ge,
                    "<": operator.lt, "<=": operator.le}


def satisfied(c: Any, ph: Any, wmi: Any) -> bool:
    """Whether condition `c` passes as a member of a skill's pre-, hold- or
    post-conditions (the optional-parameter rule included)."""
    return is_unset_optional(c, ph) or judged(c, ph, wmi)


def judged(c: Any, ph: Any, wmi: Any) -> bool:
    """Whether `c` holds as desired (False when it cannot be judged)."""
    held = holds(c, ph, wmi)
    return held is not None and held == bool(c.desired_state)


def is_unset_optional(c: Any, ph: Any) -> bool:
    if c.kind in JUDGED_WITHOUT_WORLD:
        return False
    for key in (c.subject_key, c.object_key):
        p = _param(ph, key)
        if p is not None and p.paramType == ParamTypes.Optional and (
                not p.values or (isinstance(p.values[0], Element) and p.values[0].isAbstract())):
            return True
    return False


def holds(c: Any, ph: Any, wmi: Any) -> bool | None:
    """Whether what `c` states is true of the world (before its desired state); None when
    it cannot be judged."""
    subject = _param(ph, c.subject_key)
    if c.kind in JUDGED_WITHOUT_WORLD:
        if subject is None:
            return None
        if not subject.values:
            return False
        first = subject.values[0]
        return not isinstance(first, Element) or not first.isAbstract()
    if wmi is None:
        return None
    if c.kind == "AbstractRelation":
        s, o = _concept(subject, wmi), _concept(_param(ph, c.object_key), wmi)
        if not s or not o:
            return None
        try:
            return bool(wmi.may_relate(s, c.owl, o))
        except RuntimeError:  # WorldModelError: a concept the ontology does not know relates to nothing
            return False
    sid = _element_id(subject)
    if not sid or not wmi.has_element(sid):
        return None
    if c.kind == "HasProperty":
        return wmi.get_element(sid).hasProperty(c.owl)
    if c.kind == "Property":
        e = wmi.get_element(sid)
        if not e.hasProperty(c.owl, not_none=True):
            return False
        return compare(e.getProperty(c.owl).value, c.operator, c.value)
    if c.kind == "OnType":
        return bool(wmi.is_instance_of(sid, c.owl))
    if c.kind == "Relation":
        oid = _element_id(_param(ph, c.object_key))
        if not oid or not wmi.has_element(oid):
            return None
        return bool(wmi.has_relation(sid, c.owl, oid))
    return None


def compare(have: Any, op: str, want: Any) -> bool:
    """`have` `op` `want` as the manager compares a property value with a condition's:
    two numbers by value (an int equals the same float); anything else is only equal
    (strings to strings, booleans to booleans) or not, and never ordered."""
    if _is_number(have) and _is_number(want):
        return NUMBER_OPERATORS[op](float(have), float(want)) if op in NUMBER_OPERATORS else False
    equal = type(have) is type(want) and isinstance(have, (str, bool)) and have == want
    return equal if op == "=" else (not equal) if op == "!=" else False


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _param(ph: Any, key: str) -> Param | None:
    return ph.getParamMap().get(key) if key else None  # (ph[key] would log a missing key)


def _element_id(p: Param | None) -> str:
    """The id of the element in `p`, "" when it holds no concrete element."""
    if p is None or not p.values or not isinstance(p.values[0], Element):
        return ""
    return p.values[0].id


def _concept(p: Param | None, wmi: Any) -> str:
    """The concept of the element in `p`: the world's type for a concrete element, else
    the element's type (else the parameter's default's)."""
    if p is None or not p.values or not isinstance(p.values[0], Element):
        return ""
    e = p.values[0]
    if e.id and wmi.has_element(e.id):
        return wmi.get_element(e.id).type
    return e.type or (p.default.type if isinstance(p.default, Element) else "")
