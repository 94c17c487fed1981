"""Between Element and the world model's LCM messages (lcmtypes/wm_*.lcm)."""

from __future__ import annotations

from typing import Any

from skillbus.msgs import wm_element_t, wm_op_t, wm_property_t, wm_relation_t, wm_value_t
from skillbus.world.element import Element, Property


def value_msg(v: Any, key: str) -> wm_value_t:
    m = wm_value_t()
    if isinstance(v, bool):  # before int: bool is an int in Python
        m.type, m.b = wm_value_t.BOOL, v
    elif isinstance(v, int):
        m.type, m.i = wm_value_t.INT, v
    elif isinstance(v, float):
        m.type, m.f = wm_value_t.FLOAT, v
    elif isinstance(v, str):
        m.type, m.s = wm_value_t.STRING, v
    else:
        raise TypeError(f"property {key}: a value of type {type(v).__name__} cannot be stored "
                        f"(str, int, float or bool)")
    return m


def value_from_msg(m: wm_value_t) -> Any:
    return {wm_value_t.STRING: m.s, wm_value_t.INT: m.i, wm_value_t.FLOAT: m.f, wm_value_t.BOOL: m.b}[m.type]


def property_msg(p: Property) -> wm_property_t:
    m = wm_property_t()
    m.key = p.key
    m.values = [value_msg(v, p.key) for v in p.values]
    m.num_values = len(m.values)
    return m


def element_msg(e: Element) -> wm_element_t:
    m = wm_element_t()
    m.id, m.type, m.label = e.id, e.type, e.label
    m.properties = [property_msg(p) for p in e.properties]
    m.num_properties = len(m.properties)
    return m


def element_from_msg(m: wm_element_t) -> Element:
    e = Element(m.type, m.label, m.id)
    for p in m.properties:
        e.setProperty(p.key, [value_from_msg(v) for v in p.values])
    return e


def relation_msg(s: str, p: str, o: str) -> wm_relation_t:
    r = wm_relation_t()
    r.subject, r.predicate, r.object = s, p, o
    return r


def op(kind: int, element: Element | None = None, relation: tuple[str, str, str] | None = None) -> wm_op_t:
    m = wm_op_t()
    m.kind = kind
    m.element = element_msg(element) if element is not None else wm_element_t()
    m.relation = relation_msg(*relation) if relation is not None else wm_relation_t()
    return m
