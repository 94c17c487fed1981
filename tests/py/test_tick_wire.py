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
    r.idle_until_ns = rng.choice((0, rng.randrange(-2**63, 2**63)))
    r.ended = rng.random() < 0.5
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


# -- replies made straight from a skill's Params (TickReply.of_params) ----------------------

from skillbus.skill import Param, ParamTypes  # noqa: E402
from skillbus.skill.tick_wire import element_bytes, value_bytes  # noqa: E402
from skillbus.world.convert import element_msg  # noqa: E402
from skillbus.world.element import Element  # noqa: E402

SCALARS = [lambda rng: rng.randrange(-2**63, 2**63), lambda rng: rng.uniform(-1e9, 1e9), lambda rng: rng.choice(TEXT),
           lambda rng: rng.random() < 0.5]


def an_element(rng):
    e = Element(rng.choice(TEXT) or "skiros:Cube", rng.choice(TEXT), rng.choice(TEXT))
    for k in range(rng.randrange(4)):
        make = rng.choice(SCALARS)
        e.setProperty(f"skiros:P{k}", [make(rng) for _ in range(rng.randrange(1, 3))])
    return e


def values_of_one_type(rng, kind):
    n = rng.randrange(0, 3) or 1
    if kind < 4:
        return [SCALARS[kind](rng) for _ in range(n)]
    if kind == 4:
        return [an_element(rng) for _ in range(n)]
    if kind == 5:
        return [[rng.choice(TEXT), rng.randrange(9)] for _ in range(n)]
    return [{"k": rng.choice(TEXT), "n": rng.uniform(0, 1)} for _ in range(n)]


def a_param(rng, i):
    kind = rng.randrange(7)
    values = values_of_one_type(rng, kind)
    value = values if len(values) > 1 or kind == 5 else values[0]  # (a list parameter takes lists)
    p = Param(f"P{i}", rng.choice(TEXT), value, ParamTypes(rng.randrange(3)),
              options=[rng.choice(TEXT), rng.randrange(5)][:rng.randrange(3)])
    if rng.random() < 0.3:  # values that differ from the defaults
        p.setValues(values_of_one_type(rng, kind))
    return p


def params_reply(rng):
    r = TickReply.of_params([a_param(rng, i) for i in range(rng.randrange(5))])
    r.state, r.message, r.code = rng.randrange(-128, 128), rng.choice(TEXT), rng.randrange(-2**31, 2**31)
    r.progress, r.wm_version = rng.uniform(0, 1), rng.randrange(-1, 2**40)
    r.idle_until_ns = rng.choice((0, rng.randrange(0, 2**63)))
    r.ended = rng.random() < 0.5
    return r


def test_a_reply_of_params_encodes_as_param_msg_then_the_generated_encoder():
    rng = random.Random(7)
    for _ in range(300):
        r = params_reply(rng)
        expected = skill_tick_reply_t.encode(r.as_message())
        assert r.encode() == expected
        assert skill_tick_reply_t.decode(r.encode()).num_params == len(r.skill_params)


def test_a_value_that_cannot_be_sent_fails_naming_its_type_as_param_msg_does():
    from skillbus.skill.convert import value_msg
    with pytest.raises(TypeError) as slow:
        value_msg(object())
    with pytest.raises(TypeError, match=str(slow.value)):
        value_bytes(object())
    e = Element("skiros:Cube")
    e.setProperty("skiros:Weird", [complex(1, 2)])
    with pytest.raises(TypeError, match="property skiros:Weird: a value of type complex cannot be stored"):
        element_bytes(e)
    with pytest.raises(TypeError, match="property skiros:Weird: a value of type complex cannot be stored"):
        element_msg(e)


def test_a_reader_copy_encodes_what_it_holds_without_copying_its_properties():
    src = Element("skiros:Cube", "red", "skiros:Cube-2")
    src.setProperty("skiros:Size", 0.05)
    src.setProperty("skiros:Name", ["a", "b"])
    copy = Element._reader_copy(src, (("-1", "skiros:at", "skiros:Table-1"),))
    copy.getProperty("skiros:Size").setValues(0.07)  # handed out, changed by the skill
    got = element_bytes(copy)
    assert "_properties" not in copy.__dict__  # (nothing copied to encode it)
    assert got == wm_element_t.encode(element_msg(copy))[8:]  # (element_msg makes the copy)
    assert src.getProperty("skiros:Size").value == 0.05


def test_an_untouched_reader_copy_is_encoded_once_per_source_and_a_change_is_never_missed():
    """A tick's element parameters are reader copies of the same source tick after tick:
    their bytes are kept by the source's properties, and given again only while the copy
    has neither handed out a property nor changed its names."""
    src = Element("skiros:Cube", "red", "skiros:Cube-2")
    src.setProperty("skiros:Size", [0.05, 0.06])
    src.setProperty("skiros:Name", "a")

    def fresh():
        return Element._reader_copy(src, ())

    def truth(e):
        return wm_element_t.encode(element_msg(e.clone()))[8:]

    first = element_bytes(fresh())
    assert first == truth(fresh())
    assert element_bytes(fresh()) is first  # kept: not encoded again
    relabelled = fresh()
    relabelled.label = "blue"
    assert element_bytes(relabelled) == truth(relabelled) != first
    handed = fresh()
    handed.getProperty("skiros:Size").setValue(0.5, 0)
    assert element_bytes(handed) == truth(handed) != first
    read_only = fresh()
    read_only.getProperty("skiros:Name")  # handed out, unchanged: encoded again, the same bytes
    assert element_bytes(read_only) == first
    copied = fresh()
    copied.setProperty("skiros:Mass", 1.0)  # every property copied, one added
    assert element_bytes(copied) == truth(copied) != first
    other = Element("skiros:Cube", "red", "skiros:Cube-2")  # another source: its own bytes
    other.setProperty("skiros:Size", 0.9)
    assert element_bytes(Element._reader_copy(other, ())) == truth(other) != first
    again = element_bytes(fresh())  # (the relabelled copy's bytes were kept in between)
    assert again == first and element_bytes(fresh()) is again


# -- skillbus_native's element encoder (py_tick_wire.cpp) ----------------------------------

import math  # noqa: E402

import skillbus_native  # noqa: E402  (built by make build: a test of it fails without it)

from skillbus.skill.tick_wire import python_element_bytes  # noqa: E402


class Fraction(float):
    pass


class Count(int):
    pass


class Name(str):
    pass


def same_as_python(e) -> bytes | None:
    """element_bytes(e) is Python's bytes, or raises what Python raises; the bytes."""
    try:
        want = python_element_bytes(e)
    except Exception as py_error:
        with pytest.raises(type(py_error)):
            element_bytes(e)
        return None
    assert element_bytes(e) == want
    return want


def test_the_native_element_encoder_writes_pythons_bytes_for_random_elements():
    rng = random.Random(5)
    for _ in range(500):
        e = an_element(rng)
        native = skillbus_native.element_wire(e)
        assert native is not None  # (the regular case is the native one's)
        assert native == python_element_bytes(e) == wm_element_t.encode(element_msg(e))[8:]


def test_numbers_at_their_edges_are_written_as_python_writes_them():
    e = Element("skiros:Cube", "c", "skiros:Cube-1")
    e.setProperty("skiros:F", [0.0, -0.0, math.inf, -math.inf, math.nan, 5e-324, 1.7976931348623157e308])
    e.setProperty("skiros:I", [0, -1, 2**63 - 1, -2**63])
    e.setProperty("skiros:B", [True, False])
    e.setProperty("skiros:S", ["", "\0inside", "gr\u00fc\u00dfe \U0001f916"])
    assert skillbus_native.element_wire(e) == python_element_bytes(e)


def test_what_the_native_encoder_leaves_to_python_is_written_or_refused_as_python_does():
    cases = [("subclass of float", Fraction(0.5)), ("subclass of int", Count(3)), ("subclass of str", Name("n")),
             ("an int over 64 bits", 2**63), ("a lone surrogate", "\udc80"), ("a list", [1, 2]), ("None", None)]
    for why, value in cases:
        e = Element("skiros:Cube", "c", "skiros:Cube-1")
        e.setProperty("skiros:Before", 1.0)
        e._properties["skiros:X"] = e._properties["skiros:Before"]._copy()
        e._properties["skiros:X"]._key = "skiros:X"
        e._properties["skiros:X"]._values = [value]
        assert skillbus_native.element_wire(e) is None, why
        same_as_python(e)
    odd = Element("skiros:Cube", "c", "skiros:Cube-1")
    odd.setProperty("skiros:T", 1.0)
    odd._properties["skiros:T"]._values = (1.0, 2.0)  # (a tuple: Python's loop takes it)
    assert skillbus_native.element_wire(odd) is None and same_as_python(odd) is not None
    nameless = Element("skiros:Cube", "c", "skiros:Cube-1")
    nameless._id = Name("skiros:Cube-1")
    assert skillbus_native.element_wire(nameless) is None and same_as_python(nameless) is not None
    src = Element("skiros:Cube", "red", "skiros:Cube-2")
    src.setProperty("skiros:Size", 0.05)
    reader = Element._reader_copy(src, ())
    assert skillbus_native.element_wire(reader) is None  # (its properties are still the replica's)
    assert element_bytes(reader) == python_element_bytes(reader)
    assert skillbus_native.element_wire(object()) is None and skillbus_native.element_wire(3) is None


# -- skillbus_native's parameter encoder (params_wire) ---------------------------------------

import re  # noqa: E402

from skillbus.skill import tick_wire  # noqa: E402
from skillbus.skill.tick_wire import param_bytes  # noqa: E402
from skillbus.world.property import Property  # noqa: E402


@pytest.fixture
def python_calls():
    """params_wire's fallback counted: the parameters Python's param_bytes wrote."""
    calls = []

    def counted(p):
        calls.append(p)
        return param_bytes(p)

    skillbus_native.set_param_wire(tick_wire.TYPE_NAMES, Element, counted, python_element_bytes)
    yield calls
    skillbus_native.set_param_wire(tick_wire.TYPE_NAMES, Element, param_bytes, python_element_bytes)


def same_params_as_python(params) -> bytes | None:
    """params_wire(params) is b"".join(param_bytes), or raises what Python raises."""
    try:
        want = b"".join([param_bytes(p) for p in params])
    except Exception as py_error:
        with pytest.raises(type(py_error), match=re.escape(str(py_error))):
            skillbus_native.params_wire(params)
        return None
    assert skillbus_native.params_wire(params) == want
    return want


def test_replies_use_the_native_parameter_encoder():
    assert tick_wire._params_wire is skillbus_native.params_wire


def test_the_native_parameter_encoder_writes_pythons_bytes_for_random_parameters():
    rng = random.Random(11)
    for _ in range(400):
        same_params_as_python([a_param(rng, i) for i in range(rng.randrange(6))])


def reader_copy_param(rng, handed: bool) -> Param:
    src = an_element(rng)
    copy = Element._reader_copy(src, (("-1", "skiros:at", "skiros:Table-1"),))
    if handed and src.properties:
        copy.getProperty(src.properties[0].key).setValues([0.125])  # handed out (a copy of its own), changed
    p = Param("Object", "the object", Element("skiros:Cube"), ParamTypes.Required)
    p.setValues([copy])
    return p


def test_the_regular_case_is_written_natively(python_calls):
    rng = random.Random(12)
    regular = []
    for i in range(200):
        kind = rng.randrange(5)  # int, float, str, bool, element: none left to Python
        values = values_of_one_type(rng, kind)
        p = Param(f"P{i}", rng.choice(TEXT), values if len(values) > 1 else values[0], ParamTypes(rng.randrange(3)),
                  options=[rng.choice(TEXT)][:rng.randrange(2)])
        regular.append(p)
    regular += [reader_copy_param(rng, handed) for handed in (False, True) for _ in range(20)]
    got = skillbus_native.params_wire(regular)
    assert python_calls == []  # (every one of them written in C++)
    assert got == b"".join(param_bytes(p) for p in regular)
    assert all("_properties" not in p.values[0].__dict__ for p in regular[-40:])  # (nothing copied to encode)


def test_what_the_native_parameter_encoder_leaves_to_python_is_written_or_refused_as_python_does(python_calls):
    rng = random.Random(13)
    odd = []
    json_param = Param("Poses", "a list", [[1, 2]], ParamTypes.Optional)  # lists go as JSON: Python's
    odd.append(json_param)
    odd.append(Param("Count", "", 3, ParamTypes.Required, options=[1, 2]))  # str(option): Python's
    sub = Param("Name", "", "n", ParamTypes.Required)
    sub._values = [Name("n")]  # a str subclass
    odd.append(sub)
    big = Param("Big", "", 1, ParamTypes.Required)
    big._values = [2**63]  # over 64 bits: Python's struct.error
    odd.append(big)
    surrogate = Param("Text", "\udc80", "x", ParamTypes.Required)  # not UTF-8: Python's UnicodeEncodeError
    odd.append(surrogate)
    unsendable = Param("Thing", "", 1, ParamTypes.Required)
    unsendable._values = [object()]  # a TypeError naming its type, from Python
    odd.append(unsendable)
    as_tuple = Param("Tuple", "", 1.0, ParamTypes.Required)
    as_tuple._values = (1.0, 2.0)  # (a tuple: Python's loop takes it)
    odd.append(as_tuple)
    for p in odd:
        before = len(python_calls)
        same_params_as_python([a_param(rng, 0), p, a_param(rng, 1)])
        assert any(c is p for c in python_calls[before:]), p.key
    with pytest.raises(TypeError):
        skillbus_native.params_wire((a_param(rng, 0),))  # (a list, as a reply holds them)


def test_a_kind_out_of_a_byte_or_of_64_bits_is_refused_as_python_refuses_it(python_calls):
    for kind in (128, -129, 2**63, 2**64, -2**63 - 1):
        p = Param("K", "d", 1.0, ParamTypes.Required)
        p._param_type = kind
        assert same_params_as_python([p]) is None, kind  # (struct.error, from Python)


class ChangesItsElement(Property):
    """A handed-out property whose truthiness drops it from the element that holds it: the
    encoder must hold what it reads across Python code that runs while it reads."""

    holder: dict = {}

    def __bool__(self):
        self.holder["e"].__dict__.get("_handed", {}).clear()
        return True


def test_python_code_run_while_a_parameter_is_read_changes_nothing_it_holds():
    src = Element("skiros:Cube", "red", "skiros:Cube-2")
    for i in range(4):
        src.setProperty(f"skiros:K{i}", float(i))
    copy = Element._reader_copy(src, ())
    ChangesItsElement.holder["e"] = copy
    copy.__dict__["_handed"] = {"skiros:K0": ChangesItsElement("skiros:K0", 9.0)}
    p = Param("Object", "o", Element("skiros:Cube"), ParamTypes.Required)
    p.setValues([copy])
    got = skillbus_native.params_wire([p])
    _ = [Property(f"skiros:Junk{i}", 1.0) for i in range(1000)]  # (what a freed property's memory would hold)
    assert got.count(b"skiros:K0") == 1 and b"skiros:Junk" not in got
    copy.__dict__["_handed"] = {"skiros:K0": ChangesItsElement("skiros:K0", 9.0)}
    assert got == param_bytes(p)  # (the handed-out property, as Python's `or` takes it)


class RenamesTypes(Param):
    """A parameter whose options getter changes the encoder's table of type names."""

    @property
    def options(self):
        tick_wire.TYPE_NAMES[float] = "changed-" + "x" * 40
        return []

    @options.setter
    def options(self, value):
        pass


def test_a_getter_that_changes_the_type_names_gives_pythons_bytes():
    before = dict(tick_wire.TYPE_NAMES)
    try:
        # (a name of its own, held by the table alone: replacing it frees it)
        tick_wire.TYPE_NAMES[float] = "".join(["fl", "oat"])
        native = skillbus_native.params_wire([RenamesTypes("Speed", "s", 0.5, ParamTypes.Optional)])
        tick_wire.TYPE_NAMES[float] = "".join(["fl", "oat"])
        python = param_bytes(RenamesTypes("Speed", "s", 0.5, ParamTypes.Optional))
    finally:
        tick_wire.TYPE_NAMES.clear()
        tick_wire.TYPE_NAMES.update(before)
    assert native == python and b"changed-" not in native  # (the name read before the options, as Python)
