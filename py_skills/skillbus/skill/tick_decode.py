"""Decoding the manager's ticks in a skill process, with the parameters decoded once per
distinct bytes.

A tick carries every parameter of the primitive (description, values, defaults, options;
element values with all their properties), and a task's blackboard seldom changes from
one tick to the next: the demo's ticks carry five parameters, the same bytes tick after
tick, and LCM's generated Python spent a third of a tick decoding them again
(docs/benchmarks.md). The parameters' bytes are the middle of the encoding (label,
instance, action and their count before; frame and sim time, 16 bytes, after), so they
are compared as they are, and bytes seen before give the parameters decoded then, and
checked then (skillbus.skill.process.check_params), without decoding them again.

The decoded parameters are shared between ticks with the same bytes: nothing may change
them (apply_param_msgs only reads them, and builds the skill's values afresh each tick).
"""

from __future__ import annotations

import collections
import struct

from skillbus.msgs import decode, skill_tick_t

_LABEL_AT = 8  # after the fingerprint
_TAIL = 16     # frame, sim_time_ns
_FINGERPRINT = skill_tick_t._get_packed_fingerprint()
_HEAD = struct.Struct(">qbi")  # instance, action, num_params


class TickDecoder:
    """Decodes skill_tick_t payloads; keeps the parameters of the last `keep` distinct
    parameter encodings (a process serves several primitives at once)."""

    def __init__(self, keep: int = 32) -> None:
        self.keep = keep
        self._params: collections.OrderedDict[bytes, list] = collections.OrderedDict()
        self.hits = 0

    def decode(self, payload: bytes) -> tuple[skill_tick_t, bool] | None:
        """(the tick, whether its parameters were checked before), or None when the
        payload is no skill_tick_t."""
        fast = self._split(payload)
        if fast is not None:
            label, instance, action, n, region, frame, sim_time_ns = fast
            params = self._params.get(region)
            if params is not None and len(params) == n:
                self._params.move_to_end(region)
                self.hits += 1
                t = skill_tick_t()
                t.label, t.instance, t.action = label, instance, action
                t.num_params, t.params = n, params
                t.frame, t.sim_time_ns = frame, sim_time_ns
                return t, True
        t = decode(skill_tick_t, payload)
        return None if t is None else (t, False)

    def remember(self, payload: bytes, t: skill_tick_t) -> None:
        """Keeps `t`'s parameters (decoded from `payload`, and found sound) for ticks with
        the same parameter bytes."""
        fast = self._split(payload)
        if fast is None:
            return
        region = fast[4]
        self._params[region] = t.params
        self._params.move_to_end(region)
        while len(self._params) > self.keep:
            self._params.popitem(last=False)

    @staticmethod
    def _split(payload: bytes):
        """The fields around the parameters and the parameters' bytes, or None when the
        payload is not laid out as a skill_tick_t (the full decoder then says what it is)."""
        if len(payload) < _LABEL_AT + 4 + _HEAD.size + _TAIL or payload[:_LABEL_AT] != _FINGERPRINT:
            return None
        (size,) = struct.unpack_from(">i", payload, _LABEL_AT)  # LCM: length with the NUL
        head = _LABEL_AT + 4 + size
        if size < 1 or head + _HEAD.size + _TAIL > len(payload) or payload[head - 1] != 0:
            return None
        try:
            label = payload[_LABEL_AT + 4:head - 1].decode("utf-8")
        except UnicodeDecodeError:
            return None
        instance, action, n = _HEAD.unpack_from(payload, head)
        frame, sim_time_ns = struct.unpack_from(">qq", payload, len(payload) - _TAIL)
        return label, instance, action, n, payload[head + _HEAD.size:len(payload) - _TAIL], frame, sim_time_ns
