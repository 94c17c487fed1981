"""skillbus.skill.tick_decode: a tick's parameters decoded once per distinct bytes, the
rest of the tick every time; what it gives is what LCM's decoder gives."""

from __future__ import annotations

import math
import struct

from skillbus.bus import open_bus
from skillbus.msgs import decode, skill_param_t, skill_tick_reply_t, skill_tick_t, skill_value_t, wm_element_t
from skillbus.skill.process import SkillProcess
from skillbus.skill.skill import State
from skillbus.skill.tick_decode import TickDecoder

from test_untrusted_bus import reach  # (a primitive "reach" with a float parameter Speed)


def element(eid: str) -> skill_value_t:
    v = skill_value_t()
    v.type, v.element = skill_value_t.ELEMENT, wm_element_t()
    v.element.id, v.element.type, v.element.label = eid, "skiros:Cube", "cube"
    return v


def tick_bytes(label="reach", instance=1, action=skill_tick_t.EXECUTE, frame=7, sim_time_ns=140_000_000,
               speed=0.25, objects=("skiros:Cube-1",)) -> bytes:
    t = skill_tick_t()
    t.label, t.instance, t.action, t.frame, t.sim_time_ns = label, instance, action, frame, sim_time_ns
    p = skill_param_t()
    p.key, p.data_type = "Speed", "float"
    v = skill_value_t()
    v.type, v.f = skill_value_t.FLOAT, speed
    p.values, p.num_values = [v], 1
    q = skill_param_t()
    q.key, q.data_type, q.concept = "Object", "element", "skiros:Cube"
    q.values = [element(e) for e in objects]
    q.num_values = len(q.values)
    t.params, t.num_params = [p, q], 2
    return t.encode()


def same(a: skill_tick_t, b: skill_tick_t) -> bool:
    return a.encode() == b.encode()


def test_a_tick_decodes_as_lcm_decodes_it_and_parameters_seen_before_are_not_decoded_again():
    d = TickDecoder()
    first = tick_bytes()
    t, checked = d.decode(first)
    assert not checked and same(t, decode(skill_tick_t, first))
    d.remember(first, t)
    # Another frame, instance, action and label, the same parameter bytes: taken from before.
    again = tick_bytes(label="other", instance=9, action=skill_tick_t.START, frame=8, sim_time_ns=160_000_000)
    t2, checked = d.decode(again)
    assert checked and d.hits == 1 and same(t2, decode(skill_tick_t, again))
    assert t2.params is t.params  # (shared: nothing changes them)
    # Other parameter bytes: decoded.
    changed = tick_bytes(speed=0.5)
    t3, checked = d.decode(changed)
    assert not checked and d.hits == 1 and same(t3, decode(skill_tick_t, changed))


def test_only_the_last_distinct_parameter_encodings_are_kept():
    d = TickDecoder(keep=2)
    payloads = [tick_bytes(speed=s) for s in (0.1, 0.2, 0.3)]
    for p in payloads:
        d.remember(p, d.decode(p)[0])
    assert not d.decode(payloads[0])[1]  # the oldest was forgotten
    assert d.decode(payloads[2])[1]


def test_what_is_no_tick_is_none_or_what_lcm_makes_of_it():
    d = TickDecoder()
    good = tick_bytes()
    d.remember(good, d.decode(good)[0])
    label_len = struct.unpack_from(">i", good, 8)[0]
    bad = [b"", good[:20], b"\0" * 8 + good[8:],             # short, no fingerprint
           good[:8] + struct.pack(">i", 10_000) + good[12:],  # a label longer than the message
           good[:8] + struct.pack(">i", -3) + good[12:],
           good[:8] + struct.pack(">i", label_len - 1) + good[12:],  # no NUL where the label ends
           good[:-1], good + b"\0"]
    for p in bad:
        got = d.decode(p)
        want = decode(skill_tick_t, p)
        assert (got is None) == (want is None), p
        if got is not None:
            assert same(got[0], want)
    # The same parameter bytes behind a count that does not match them: decoded in full.
    head = 8 + 4 + label_len + 8 + 1
    miscounted = good[:head] + struct.pack(">i", 3) + good[head + 4:]
    assert d.decode(miscounted) is None and decode(skill_tick_t, miscounted) is None


def test_parameters_that_were_refused_are_checked_again_every_time():
    """Through the process's RPC method: a tick whose values were refused is refused again
    (its parameters are not remembered as sound); a sound one runs, and its parameters are
    then taken from before."""
    reach.started.clear()
    proc = SkillProcess(open_bus("memq://"), "t", ["test_untrusted_bus"])
    tick = proc.server.methods["tick"]
    bad = tick_bytes(action=skill_tick_t.START, frame=-1, speed=math.nan)
    for _ in range(2):
        r = decode(skill_tick_reply_t, tick(bad))
        assert r.state == int(State.Failure) and "refused the tick" in r.message
    assert reach.started == [] and proc._ticks.hits == 0
    good = tick_bytes(action=skill_tick_t.START, frame=-1)
    tick(good)
    tick(tick_bytes(action=skill_tick_t.EXECUTE, frame=-1))
    assert reach.started == [0.25] and proc._ticks.hits == 1
