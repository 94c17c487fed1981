"""A skill process's tick replies onto the wire, fast.

Why an encoder of our own: a skill process answers every tick of the manager with a
``skill_tick_reply_t`` that carries every parameter of the skill (each value a
``skill_value_t``, an element one with its ``wm_element_t``), and LCM's generated Python
encodes it field by field through a BytesIO: about a quarter of a tick's time in the skill
process (docs/skills.md). This writes exactly the bytes of the generated encoder from the
same objects, with precompiled structs into one join; tests/py/test_tick_wire.py compares
both on random replies. ``TickReply`` is a ``skill_tick_reply_t`` whose ``encode()`` is
this one.
"""

from __future__ import annotations

import struct

from skillbus.msgs import skill_param_t, skill_tick_reply_t, skill_value_t, wm_element_t, wm_value_t

_FINGERPRINT = skill_tick_reply_t._get_packed_fingerprint()
_U32 = struct.Struct(">I").pack
_I32 = struct.Struct(">i").pack
_B = struct.Struct(">b").pack
_QDB = struct.Struct(">qdb").pack
_IDQI = struct.Struct(">idqi").pack


def _string(out: list, s: str) -> None:
    b = s.encode("utf-8")
    out += (_U32(len(b) + 1), b, b"\0")


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
    out.append(_IDQI(r.code, r.progress, r.wm_version, r.num_params))
    for i in range(r.num_params):
        _param(out, r.params[i])
    return b"".join(out)


class TickReply(skill_tick_reply_t):
    """A skill_tick_reply_t encoded by encode_tick_reply."""

    def encode(self) -> bytes:
        return encode_tick_reply(self)
