"""Between Element and the world model's LCM messages (lcmtypes/wm_*.lcm)."""

from __future__ import annotations

from typing import Any

from skillbus.msgs import wm_element_t, wm_op_t, wm_property_t, wm_relation_t, wm_value_t
from skillbus.validate import BadValue, finite, one_of, text
from skillbus.world.element import Element, Property

VALUE_TYPES = (wm_value_t.STRING, wm_value_t.INT, wm_value_t.FLOAT, wm_value_t.BOOL)
OP_KINDS = (wm_op_t.ADD_ELEMENT, wm_op_t.UPDATE_ELEMENT, wm_op_t.REMOVE_ELEMENT, wm_op_t.ADD_RELATION,
            wm_op_t.REMOVE_RELATION)


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


# Which field holds a value of each type (an unknown type is a KeyError, as ever).
_VALUE_FIELD = {wm_value_t.STRING: "s", wm_value_t.INT: "i", wm_value_t.FLOAT: "f", wm_value_t.BOOL: "b"}


def value_from_msg(m: wm_value_t) -> Any:
    return getattr(m, _VALUE_FIELD[m.type])


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
    """The element a message carries (a skill's parameter at every tick: built as the
    replica's elements are, without setProperty's checks, which a value off the wire never
    needs). A key given twice is built by setProperty (its last values, the first one's
    type), as it always was."""
    field = _VALUE_FIELD
    new_property = Property._from_wire
    props = {}
    for p in m.properties:
        if p.key in props:
            return _element_by_set_property(m)
        props[p.key] = new_property(p.key, [getattr(v, field[v.type]) for v in p.values])
    return Element._from_wire(m.type, m.label, m.id, props)


def _element_by_set_property(m: wm_element_t) -> Element:
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


def check_element_msg(m: wm_element_t, name: str = "element", need_id: bool = True) -> None:
    """Raises BadValue unless every value of `m` is one element_from_msg can take: a known
    type (an unknown one was a KeyError inside the receiver) and, for a FLOAT, a finite
    number (a NaN pose makes every transform through it NaN); and, with `need_id`, an id."""
    if need_id:
        text(m.id, f"{name}.id")
    for p in m.properties:
        for i, v in enumerate(p.values):
            where = f"{name}.{p.key}[{i}]"
            one_of(v.type, f"{where}.type", VALUE_TYPES)
            if v.type == wm_value_t.FLOAT:
                finite(v.f, where)


def check_op_msg(o: wm_op_t, name: str = "op") -> None:
    """Raises BadValue unless `o` is an operation a replica can apply: a known kind, an
    element with an id and sane values (element operations), a relation with all three
    parts (relation operations)."""
    one_of(o.kind, f"{name}.kind", OP_KINDS)
    if o.kind in (wm_op_t.ADD_RELATION, wm_op_t.REMOVE_RELATION):
        for part in ("subject", "predicate", "object"):
            text(getattr(o.relation, part), f"{name}.relation.{part}")
    else:
        check_element_msg(o.element, f"{name}.element")
