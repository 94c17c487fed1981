"""skillbus.skill.tick_wire writes exactly what LCM's generated encoder writes."""

import random

import pytest

from skillbus.msgs import skill_param_t, skill_tick_reply_t, skill_value_t, wm_element_t, wm_property_t, wm_value_t
from skillbus.skill.tick_wire import TickReply, encode_tick_reply

TEXT = ["", "a", "skiros:Cube-2", "gr\u00fc\u00dfe", "x" * 300]


def wm_value(rng):
    v = wm_value_t()
    v.type = rng.randrange(4)
    v.s, v.i, v.f, v.b = rng.choice(TEXT), rng.randrange(-2**63, 2**63), rng.uniform(-1e9, 1e9), rng.random() < 0.5
    return v


def element(rng):
    e = wm_element_t()
    e.id, e.type, e.label = rng.choice(TEXT), rng.choice(TEXT), rng.choice(TEXT)
    for _ in range(rng.randrange(4)):
        p = wm_property_t()
        p.key = rng.choice(TEXT)
        p.values = [wm_value(rng) for _ in range(rng.randrange(3))]
        p.num_values = len(p.values)
        e.properties.append(p)
    e.num_properties = len(e.properties)
    return e


def value(rng):
    v = skill_value_t()
    v.type = rng.randrange(6)
    v.s, v.i, v.f, v.b = rng.choice(TEXT), rng.randrange(-2**63, 2**63), rng.uniform(-1e9, 1e9), rng.random() < 0.5
    if rng.random() < 0.5:
        v.element = element(rng)
    return v


def reply(rng, cls=skill_tick_reply_t):
    r = cls()
    r.state, r.message, r.code = rng.randrange(-128, 128), rng.choice(TEXT), rng.randrange(-2**31, 2**31)
    r.progress, r.wm_version = rng.uniform(0, 1), rng.randrange(-1, 2**40)
    for _ in range(rng.randrange(5)):
        p = skill_param_t()
        p.key, p.description, p.data_type, p.concept = (rng.choice(TEXT) for _ in range(4))
        p.param_type = rng.randrange(3)
        p.values = [value(rng) for _ in range(rng.randrange(3))]
        p.num_values = len(p.values)
        p.defaults = [value(rng) for _ in range(rng.randrange(2))]
        p.num_defaults = len(p.defaults)
        p.options = [rng.choice(TEXT) for _ in range(rng.randrange(3))]
        p.num_options = len(p.options)
        r.params.append(p)
    r.num_params = len(r.params)
    return r


def test_replies_encode_as_the_generated_encoder_encodes_them():
    rng = random.Random(5)
    for _ in range(300):
        r = reply(rng)
        assert encode_tick_reply(r) == r.encode()


def test_a_tick_reply_is_a_skill_tick_reply_t_that_encodes_fast():
    r = reply(random.Random(6), TickReply)
    assert isinstance(r, skill_tick_reply_t)
    assert r.encode() == skill_tick_reply_t.encode(r)
    assert skill_tick_reply_t.decode(r.encode()).num_params == r.num_params


def test_a_number_out_of_range_fails_as_it_does_in_the_generated_encoder():
    r = skill_tick_reply_t()
    r.code = 2**31
    with pytest.raises(Exception) as generated:
        r.encode()
    with pytest.raises(type(generated.value)):
        encode_tick_reply(r)
