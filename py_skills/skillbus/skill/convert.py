"""Between the skill SDK's objects and the skill messages (lcmtypes/skill_*.lcm)."""

from __future__ import annotations

import json
from typing import Any

from skillbus.msgs import (skill_condition_t, skill_description_t, skill_param_t, skill_tree_node_t, skill_tree_t,
                           skill_value_t)
from skillbus.skill.conditions import ConditionBase, ConditionOr
from skillbus.skill.params import Param, ParamTypes
from skillbus.skill.skill import SkillBase, SkillCore, SkillWrapper
from skillbus.world.convert import element_from_msg, element_msg
from skillbus.world.element import Element

TYPE_NAMES = {int: "int", float: "float", str: "str", bool: "bool", list: "list", dict: "dict", Element: "element"}
NAME_TYPES = {v: k for k, v in TYPE_NAMES.items()}


def value_msg(v: Any) -> skill_value_t:
    m = skill_value_t()
    if isinstance(v, bool):
        m.type, m.b = skill_value_t.BOOL, v
    elif isinstance(v, int):
        m.type, m.i = skill_value_t.INT, v
    elif isinstance(v, float):
        m.type, m.f = skill_value_t.FLOAT, v
    elif isinstance(v, str):
        m.type, m.s = skill_value_t.STRING, v
    elif isinstance(v, Element):
        m.type, m.element = skill_value_t.ELEMENT, element_msg(v)
    elif isinstance(v, (list, dict)):
        m.type, m.s = skill_value_t.JSON, json.dumps(v, sort_keys=True)
    else:
        raise TypeError(f"a parameter value of type {type(v).__name__} cannot be sent")
    return m


def value_from_msg(m: skill_value_t) -> Any:
    if m.type == skill_value_t.ELEMENT:
        return element_from_msg(m.element)
    if m.type == skill_value_t.JSON:
        return json.loads(m.s)
    return {skill_value_t.STRING: m.s, skill_value_t.INT: m.i, skill_value_t.FLOAT: m.f,
            skill_value_t.BOOL: m.b}[m.type]


def param_msg(p: Param) -> skill_param_t:
    m = skill_param_t()
    m.key, m.description, m.param_type = p.key, p.description, int(p.paramType)
    m.data_type = TYPE_NAMES[p.dataType()]
    if p.dataTypeIs(Element) and p.getDefaultValues():
        m.concept = p.getDefaultValue().type
    m.values = [value_msg(v) for v in p.values]
    m.num_values = len(m.values)
    m.defaults = [value_msg(v) for v in p.getDefaultValues()]
    m.num_defaults = len(m.defaults)
    m.options = [str(o) for o in p.options]
    m.num_options = len(m.options)
    return m


def specify_msg(key: str, value: Any) -> skill_param_t:
    """A value fixed by a compound's `specify`."""
    m = skill_param_t()
    m.key = key
    m.data_type = TYPE_NAMES.get(type(value), "str")
    m.values = [value_msg(v) for v in (value if isinstance(value, list) and not isinstance(value, str) else [value])]
    m.num_values = len(m.values)
    return m


def apply_param_msgs(skill: SkillCore, params: list[skill_param_t]) -> None:
    """Sets the skill's parameter values from the manager's (unknown keys are ignored).
    Element values come with the properties the manager has; with a world-model client
    they also get the relations of this process's replica. Either way they remember what
    they carried, so an update writes only what the skill changed."""
    wmi = skill.wmi
    # (a world-model client's: a new element each tick, decoded once per message)
    tick_element = getattr(wmi, "tick_element", None)
    for m in params:
        if skill.params.hasParam(m.key):
            p = skill.params[m.key]
            values = []
            for msg in m.values:
                if tick_element is not None and msg.type == skill_value_t.ELEMENT and msg.element.id:
                    values.append(tick_element(msg.element))
                    continue
                v = value_from_msg(msg)
                if isinstance(v, Element) and not v.isAbstract():  # (made afresh just now: completed in place)
                    if wmi is not None:
                        wmi.add_relations(v)
                    else:
                        v.mark_loaded()
                values.append(v)
            p._values = values  # from the blackboard, already checked by the manager


def condition_msgs(conditions: list[ConditionBase]) -> list[skill_condition_t]:
    """The conditions as the manager takes them: a ConditionOr becomes its members, marked
    with one or_label that no other ConditionOr of the list has (the manager groups a run
    of members by it; SkiROS2 labels every ConditionOr "or")."""
    out = []
    or_labels: set[str] = set()
    for c in conditions:
        members, or_label = ([c], "")
        if isinstance(c, ConditionOr):
            _check_or(c)
            members, or_label = c.conditions, c.label
            n = 1
            while or_label in or_labels:
                n += 1
                or_label = f"{c.label} ({n})"
            or_labels.add(or_label)
        for x in members:
            m = skill_condition_t()
            m.kind, m.label, m.subject, m.object = x.kind, x.label, x.subject_key, x.object_key
            m.owl, m.op, m.desired_state, m.or_label = x.owl, x.operator, x.desired_state, or_label
            m.value = value_msg(x.value) if x.value is not None else skill_value_t()
            out.append(m)
    return out


def _check_or(c: ConditionOr) -> None:
    """What the manager cannot check is refused when the skill registers, not misjudged."""
    if not c.conditions:
        raise ValueError(f"ConditionOr {c.label!r} has no conditions: it can never hold (addCondition its members)")
    if not c.desired_state:
        raise ValueError(f"ConditionOr {c.label!r}: desired_state False is not supported by the skill manager; "
                         f"add its members as separate conditions, each with the opposite desired state")
    if any(isinstance(x, ConditionOr) for x in c.conditions):
        raise ValueError(f"ConditionOr {c.label!r}: a ConditionOr inside another is not supported by the skill "
                         f"manager")


def description_msg(skill: SkillCore) -> skill_description_t:
    d = skill.description
    m = skill_description_t()
    m.type, m.label, m.compound = skill.type, skill.label, isinstance(skill, SkillBase)
    m.params = [param_msg(p) for _, p in d.params.items()]
    m.num_params = len(m.params)
    m.pre, m.hold, m.post = (condition_msgs(d.preConditions), condition_msgs(d.holdConditions),
                             condition_msgs(d.postConditions))
    m.num_pre, m.num_hold, m.num_post = len(m.pre), len(m.hold), len(m.post)
    m.not_for_planning = not getattr(skill, "available_for_planning", True)
    return m


def tree_msg(root: SkillWrapper) -> skill_tree_t:
    t = skill_tree_t()

    def walk(node: SkillWrapper, parent: int) -> None:
        n = skill_tree_node_t()
        n.type, n.label, n.processor, n.parent = node.type, node.label, node.processor.spec(), parent
        remaps = node.remaps
        n.remap_from = list(remaps)
        n.remap_to = [remaps[k] for k in n.remap_from]
        n.num_remaps = len(n.remap_from)
        n.specify = [specify_msg(k, v) for k, v in node.specified.items()]
        n.num_specify = len(n.specify)
        n.pre, n.hold, n.post = (condition_msgs(node.conditions["pre"]), condition_msgs(node.conditions["hold"]),
                                 condition_msgs(node.conditions["post"]))
        n.num_pre, n.num_hold, n.num_post = len(n.pre), len(n.hold), len(n.post)
        t.nodes.append(n)
        me = len(t.nodes) - 1
        for c in node.children:
            walk(c, me)

    walk(root, -1)
    t.num_nodes = len(t.nodes)
    return t
