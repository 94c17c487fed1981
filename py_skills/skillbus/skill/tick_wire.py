"""A skill process's tick replies onto the wire, fast.

Why an encoder of our own: a skill process answers every tick of the manager with a
``skill_tick_reply_t`` that carries every parameter of the skill (each value a
``skill_value_t``, an element one with its ``wm_element_t``), and LCM's generated Python
encodes it field by field through a BytesIO: about a quarter of a tick's time in the skill
process (docs/skills.md). This writes exactly the bytes of the generated encoder from the
same objects, with precompiled structs into one join; tests/py/test_tick_wire.py compares
both on random replies. ``TickReply`` is a ``skill_tick_reply_t`` whose ``encode()`` is
this one.

A skill process's reply is made from the skill's own ``Param`` objects: building the
messages (``convert.param_msg``: a ``skill_param_t``, ``skill_value_t``, ``wm_element_t``,
... per value, each with every field set) cost as much again as encoding them. So
``TickReply.of_params`` keeps the Params, and ``encode()`` writes their bytes straight
from them (``param_bytes``): the same bytes as ``param_msg`` then LCM's encoder, and the
same errors (a value that cannot be sent is a TypeError naming it).
"""

from __future__ import annotations

import json
import struct
from typing import Any, Iterable

from skillbus import native
from skillbus.msgs import skill_param_t, skill_tick_reply_t, skill_value_t, wm_element_t, wm_value_t
from skillbus.skill.convert import TYPE_NAMES, param_msg
from skillbus.skill.param import Param
from skillbus.world.element import Element

# skillbus_native's element encoder (None: not built, or SKILLBUS_NATIVE=0 at start).
_element_wire = getattr(native.module(), "element_wire", None)
_FINGERPRINT = skill_tick_reply_t._get_packed_fingerprint()
_U32 = struct.Struct(">I").pack
_I32 = struct.Struct(">i").pack
_B = struct.Struct(">b").pack
_QDB = struct.Struct(">qdb").pack
_REPLY_NUMBERS = struct.Struct(">idqqbi").pack  # code, progress, wm_version, idle_until_ns, ended, num_params


def _encode_text(s: str) -> bytes:
    b = s.encode("utf-8")
    return _U32(len(b) + 1) + b + b"\0"


def _string(out: list, s: str) -> None:
    out.append(_encode_text(s))


def _element(out: list, e: wm_element_t) -> None:
    _string(out, e.id)
    _string(out, e.type)
    _string(out, e.label)
    out.append(_I32(e.num_properties))
    for i in range(e.num_properties):
        p = e.properties[i]
        _string(out, p.key)
        out.append(_I32(p.num_values))
        for j in range(p.num_values):
            v: wm_value_t = p.values[j]
            out.append(_B(v.type))
            _string(out, v.s)
            out.append(_QDB(v.i, v.f, v.b))


def _value(out: list, v: skill_value_t) -> None:
    out.append(_B(v.type))
    _string(out, v.s)
    out.append(_QDB(v.i, v.f, v.b))
    _element(out, v.element)


def _param(out: list, p: skill_param_t) -> None:
    _string(out, p.key)
    _string(out, p.description)
    out.append(_B(p.param_type))
    _string(out, p.data_type)
    _string(out, p.concept)
    out.append(_I32(p.num_values))
    for i in range(p.num_values):
        _value(out, p.values[i])
    out.append(_I32(p.num_defaults))
    for i in range(p.num_defaults):
        _value(out, p.defaults[i])
    out.append(_I32(p.num_options))
    for i in range(p.num_options):
        _string(out, p.options[i])


def encode_tick_reply(r: skill_tick_reply_t) -> bytes:
    """The bytes ``skill_tick_reply_t.encode`` gives for `r` (and its errors: a number out
    of its field's range is a struct.error)."""
    out: list = [_FINGERPRINT, _B(r.state)]
    _string(out, r.message)
    out.append(_REPLY_NUMBERS(r.code, r.progress, r.wm_version, r.idle_until_ns, bool(r.ended), r.num_params))
    for i in range(r.num_params):
        _param(out, r.params[i])
    return b"".join(out)


# -- straight from the skill's Params ------------------------------------------------------

# A string's bytes by its value: keys, descriptions, concepts, ids and labels come back
# every tick. Pure (a str is immutable), bounded, and only for short strings.
_TEXTS: dict[str, bytes] = {}
_TEXTS_MAX, _TEXT_MAX_CHARS = 8192, 256


def _text(s: str) -> bytes:
    b = _TEXTS.get(s)
    if b is None:
        b = _encode_text(s)
        if len(_TEXTS) < _TEXTS_MAX and len(s) <= _TEXT_MAX_CHARS and type(s) is str:
            _TEXTS[s] = b
    return b


_EMPTY = _text("")
_NO_NUMBERS = _QDB(0, 0.0, False)
_NO_PROPERTIES = _I32(0)
_NO_ELEMENT = _EMPTY * 3 + _NO_PROPERTIES  # wm_element_t(): an empty id, type and label, no properties
_SKILL = skill_value_t
_WM = wm_value_t
# The bytes before a value's numbers: its type and an empty string.
_WM_BOOL, _WM_INT, _WM_FLOAT = (_B(t) + _EMPTY for t in (_WM.BOOL, _WM.INT, _WM.FLOAT))
_WM_STRING = _B(_WM.STRING)
_SK_BOOL, _SK_INT, _SK_FLOAT = (_B(t) + _EMPTY for t in (_SKILL.BOOL, _SKILL.INT, _SKILL.FLOAT))
_SK_STRING, _SK_JSON = _B(_SKILL.STRING), _B(_SKILL.JSON)
_SK_ELEMENT = _B(_SKILL.ELEMENT) + _EMPTY + _NO_NUMBERS
_TAIL = _NO_NUMBERS + _NO_ELEMENT


def _wm_value(v: Any, key: str) -> bytes:
    """A property value as world/convert.value_msg makes it, encoded."""
    t = type(v)  # (the exact types first: most values; then the subclasses, as value_msg's order)
    if t is float or (t is not bool and t is not int and t is not str and isinstance(v, float)):
        return _WM_FLOAT + _QDB(0, v, False)
    if isinstance(v, bool):  # (before int: a bool is an int)
        return _WM_BOOL + _QDB(0, 0.0, v)
    if isinstance(v, int):
        return _WM_INT + _QDB(v, 0.0, False)
    if isinstance(v, str):
        return _WM_STRING + _text(v) + _NO_NUMBERS
    raise TypeError(f"property {key}: a value of type {type(v).__name__} cannot be stored "
                    f"(str, int, float or bool)")


def element_bytes(e: Element) -> bytes:
    """What world/convert.element_msg(e) encodes to (a reader copy is not copied for it):
    skillbus_native's encoder when it takes the element, else Python's."""
    if _element_wire is not None:
        b = _element_wire(e)
        if b is not None:
            return b
    return python_element_bytes(e)


# The bytes of reader copies whose properties are all still their source's, by that source's
# properties dict: id(dict) -> (the dict, (id, type, label), bytes). A source's dict is never
# changed in place (the replica replaces an element that changes; a tick's decoded element is
# nobody's to change: WorldModelInterface.tick_element), and it is kept alive here, so its id
# names no other dict. A tick's element parameters are such copies, the same tick after tick.
_UNREAD_BYTES: dict[int, tuple[dict, tuple[str, str, str], bytes]] = {}
_UNREAD_BYTES_KEPT = 256


def python_element_bytes(e: Element) -> bytes:
    """element_bytes in Python: for what the native encoder leaves (a reader copy, a value
    of a subclass or of a type that cannot be stored, text that is not UTF-8)."""
    d = e.__dict__
    if "_properties" not in d and not d.get("_handed"):
        unread = e._unread()
        if unread is not None:  # (a reader copy that has handed out no property)
            names = (e._id, e._type, e._label)
            kept = _UNREAD_BYTES.get(id(unread))
            if kept is not None and kept[0] is unread and kept[1] == names:
                return kept[2]
            b = _element_bytes_of(e, unread.values())
            if len(_UNREAD_BYTES) >= _UNREAD_BYTES_KEPT:
                _UNREAD_BYTES.clear()
            _UNREAD_BYTES[id(unread)] = (unread, names, b)
            return b
    return _element_bytes_of(e, d["_properties"].values() if "_properties" in d else e._wire_properties())


def _element_bytes_of(e: Element, props: Any) -> bytes:
    text = _text
    if not props:  # (abstract parameters' elements, most defaults: nothing but the names)
        return text(e._id) + text(e._type) + text(e._label) + _NO_PROPERTIES
    wm_value = _wm_value
    out = [text(e._id), text(e._type), text(e._label), _I32(len(props))]
    for p in props:
        key, values = p._key, p._values
        out.append(text(key))
        out.append(_I32(len(values)))
        out += [wm_value(v, key) for v in values]
    return b"".join(out)


def value_bytes(v: Any) -> bytes:
    """What skill/convert.value_msg(v) encodes to."""
    if isinstance(v, Element):
        return _SK_ELEMENT + element_bytes(v)
    if isinstance(v, bool):
        return _SK_BOOL + _QDB(0, 0.0, v) + _NO_ELEMENT
    if isinstance(v, int):
        return _SK_INT + _QDB(v, 0.0, False) + _NO_ELEMENT
    if isinstance(v, float):
        return _SK_FLOAT + _QDB(0, v, False) + _NO_ELEMENT
    if isinstance(v, str):
        return _SK_STRING + _text(v) + _TAIL
    if isinstance(v, (list, dict)):
        return _SK_JSON + _text(json.dumps(v, sort_keys=True)) + _TAIL
    raise TypeError(f"a parameter value of type {type(v).__name__} cannot be sent")


def param_bytes(p: Param) -> bytes:
    """What skill/convert.param_msg(p) encodes to."""
    text = _text
    defaults = p._default
    data_type = p._type
    concept = defaults[0].type if data_type is Element and defaults else ""
    values = p._values
    out = [text(p._key), text(p.description), _B(p._param_type), text(TYPE_NAMES[data_type]), text(concept),
           _I32(len(values))]
    out += [value_bytes(v) for v in values]
    out.append(_I32(len(defaults)))
    out += [value_bytes(v) for v in defaults]
    options = p.options
    out.append(_I32(len(options)))
    out += [text(str(o)) for o in options]
    return b"".join(out)


class TickReply(skill_tick_reply_t):
    """A skill_tick_reply_t encoded by encode_tick_reply, or, made by `of_params`, one
    whose parameters are the skill's Params, encoded straight from them."""

    __slots__ = ("skill_params",)

    def __init__(self) -> None:
        super().__init__()
        self.skill_params: list[Param] | None = None

    @classmethod
    def of_params(cls, params: Iterable[Param]) -> "TickReply":
        """A reply carrying `params` (their values as they are when it is encoded); its
        `params` field stays empty (`as_message` makes the messages)."""
        r = cls()
        r.skill_params = list(params)
        return r

    def as_message(self) -> skill_tick_reply_t:
        """The reply as LCM's generated type, its parameters as convert.param_msg makes them."""
        m = skill_tick_reply_t()
        m.state, m.message, m.code, m.progress, m.wm_version, m.idle_until_ns, m.ended = (
            self.state, self.message, self.code, self.progress, self.wm_version, self.idle_until_ns, self.ended)
        m.params = [param_msg(p) for p in self.skill_params] if self.skill_params is not None else list(self.params)
        m.num_params = len(m.params)
        return m

    def encode(self) -> bytes:
        if self.skill_params is None:
            return encode_tick_reply(self)
        head = (_FINGERPRINT + _B(self.state) + _encode_text(self.message) +
                _REPLY_NUMBERS(self.code, self.progress, self.wm_version, self.idle_until_ns, bool(self.ended),
                               len(self.skill_params)))
        if _params_wire is not None:
            return head + _params_wire(self.skill_params)
        return head + b"".join([param_bytes(p) for p in self.skill_params])


def _native_params_wire():
    """skillbus_native's params_wire, given what it reads types by and falls back to; None
    without it."""
    lib = native.module()
    if lib is None or not hasattr(lib, "params_wire"):
        return None
    lib.set_param_wire(TYPE_NAMES, Element, param_bytes, python_element_bytes)
    return lib.params_wire


# The parameters of a reply written by skillbus_native (the regular case; param_bytes for
# the rest), or by param_bytes alone.
_params_wire = _native_params_wire()
