"""skillbus.validate: the checks every receiver runs on the values it acts on (finite
numbers within their range, integers, codes, text, poses) and the counter of what it
dropped (counted per kind, logged once per kind with the value escaped)."""

from __future__ import annotations

import logging
import math

import pytest

from skillbus.validate import MAX_KINDS, BadValue, Rejects, finite, finite_all, integer, one_of, pose, shown, text

NOT_FINITE = [math.nan, math.inf, -math.inf]


@pytest.mark.parametrize("value", NOT_FINITE + [10 ** 400])
def test_finite_refuses_nan_infinities_and_ints_beyond_a_double(value):
    with pytest.raises(BadValue, match=r"^width=.*: not a finite number$") as e:
        finite(value, "width")
    assert e.value.name == "width" and e.value.why == "not a finite number"


@pytest.mark.parametrize("value", NOT_FINITE)
def test_a_range_does_not_let_nan_or_infinities_through(value):
    # (NaN fails every comparison: a range check alone would pass it)
    with pytest.raises(BadValue):
        finite(value, "x", -1.0, 1.0)


def test_finite_checks_the_range_and_returns_a_float():
    assert finite(3, "x", 0, 5) == 3.0 and isinstance(finite(3, "x"), float)
    assert finite(-0.0, "x", 0.0, 1.0) == 0.0
    with pytest.raises(BadValue, match=r"^x=-0\.001: below 0$"):
        finite(-0.001, "x", 0.0, 1.0)
    with pytest.raises(BadValue, match=r"^x=1e\+300: above 1$"):
        finite(1e300, "x", 0.0, 1.0)


@pytest.mark.parametrize("value", ["1.0", None, True, [1.0], b"\x00"])
def test_finite_refuses_what_is_not_a_number(value):
    with pytest.raises(BadValue, match="not a number"):
        finite(value, "x")


def test_integer_refuses_floats_bools_and_out_of_range():
    assert integer(7, "n", 0, 7) == 7
    for bad in (7.0, True, "7", None):
        with pytest.raises(BadValue, match="not an integer"):
            integer(bad, "n")
    with pytest.raises(BadValue, match=r"^n=-1: below 0$"):
        integer(-1, "n", 0)
    with pytest.raises(BadValue, match=r"^n=2147483647: above 10000$"):
        integer(2 ** 31 - 1, "n", 0, 10_000)


def test_finite_all_names_the_bad_element_and_checks_the_length():
    assert finite_all([0.1, 0.2], "q", -1, 1, length=2) == [0.1, 0.2]
    with pytest.raises(BadValue, match=r"^q\[1\]=nan: not a finite number$"):
        finite_all([0.1, math.nan], "q")
    with pytest.raises(BadValue, match=r"^q='3 values': 2 expected$"):
        finite_all([0.0, 0.0, 0.0], "q", length=2)


def test_finite_all_answers_as_checking_each_value_does():
    # finite_all takes a shortcut when every value is a float in range; whatever the
    # values, it must give what checking them one by one gives: the same list or the same
    # error, naming the first bad value.
    import random

    def one_by_one(values, name, lo=None, hi=None, length=None):
        out = [finite(v, f"{name}[{i}]", lo, hi) for i, v in enumerate(values)]
        if length is not None and len(out) != length:
            raise BadValue(name, f"{len(out)} values", f"{length} expected")
        return out

    def outcome(f, *args, **kw):
        try:
            got = f(*args, **kw)
            return "ok", got, [type(v) for v in got]
        except BadValue as e:
            return "bad", str(e)

    rng = random.Random(20261204)
    pool = [0.0, 0.5, -0.5, 1.0, -1.0, 2.5, -2.5, 1e300, math.nan, math.inf, -math.inf, 1, 0, -3, True, False,
            2 ** 1100, "1.0", None]
    for _ in range(5000):
        values = [rng.choice(pool) for _ in range(rng.randint(0, 5))]
        lo, hi = rng.choice([(None, None), (-1.0, 1.0), (-2, None), (None, 2)])
        length = rng.choice([None, len(values), 3])
        values = values if rng.random() < 0.5 else tuple(values)
        assert outcome(finite_all, values, "q", lo, hi, length=length) == outcome(one_by_one, values, "q", lo, hi,
                                                                                   length=length), (values, lo, hi)
    assert finite_all(iter([0.25, 0.5]), "q") == [0.25, 0.5]  # any iterable, as before

    def values_then_trouble():  # checked lazily: the bad value is named before the rest is read
        yield 0.5
        yield math.nan
        raise RuntimeError("read past the bad value")

    with pytest.raises(BadValue, match=r"^q\[1\]=nan"):
        finite_all(values_then_trouble(), "q")
    with pytest.raises(BadValue, match=r"^p\.y=3\.0: above 2$"):
        pose([0.0, 3.0, 0.0, 0.0, 0.0, 0.0, 1.0], "p", 2.0)
    assert pose([0.0, 2.0, -2.0, 0.0, 0.0, 0.0, 1.0], "p", 2.0)[1] == 2.0


def test_one_of_and_text():
    assert one_of(1, "mode", (1,)) == 1
    with pytest.raises(BadValue, match=r"^mode=7: not one of 1, 3$"):
        one_of(7, "mode", (1, 3))
    assert text("a", "name") == "a" and text("", "name", nonempty=False) == ""
    with pytest.raises(BadValue, match="empty"):
        text("", "name")
    with pytest.raises(BadValue, match="not a string"):
        text(b"a", "name")


def test_pose_wants_finite_numbers_a_reach_and_a_unit_quaternion():
    assert pose([1, 2, 3, 0, 0, 0, 1], "p", 10) == [1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0]
    with pytest.raises(BadValue, match=r"^p\.z=1000000\.0: above 10$"):
        pose([0, 0, 1e6, 0, 0, 0, 1], "p", 10)
    with pytest.raises(BadValue, match=r"^p\.rotation=.*: not a unit quaternion \(norm 0\)$"):
        pose([0, 0, 0, 0, 0, 0, 0], "p", 10)
    with pytest.raises(BadValue, match=r"^p\[6\]=nan"):
        pose([0, 0, 0, 0, 0, 0, math.nan], "p", 10)
    with pytest.raises(BadValue, match=r"^p='6 values': 7 expected$"):
        pose([0, 0, 0, 0, 0, 1], "p", 10)


def test_values_are_shown_escaped_and_cut():
    assert shown("a\nb\x1b[31m") == repr("a\nb\x1b[31m") and "\n" not in shown("a\nb")
    long = shown("x" * 1000)
    assert len(long) == 80 and long.endswith("...")
    assert str(BadValue("label", "evil\r\ninjected line", "empty")) == "label='evil\\r\\ninjected line': empty"


def test_rejects_count_per_kind_and_log_each_kind_once(caplog):
    r = Rejects("test-receiver")
    with caplog.at_level(logging.WARNING, logger="test-receiver"):
        for v in (math.inf, math.nan, -math.inf):
            try:
                finite(v, "finger_width", 0, 0.08)
            except BadValue as e:
                r.record("SB_X", e)
        r.record("SB_X", BadValue("finger_force", 1e300, "above 6553.5"))
        r.record("RPDO1", "not a can_sync_t")
    assert r.total == 5
    assert r.summary() == {"RPDO1: not a can_sync_t": 1, "SB_X: finger_force": 1, "SB_X: finger_width": 3}
    lines = [rec.getMessage() for rec in caplog.records]
    assert len(lines) == 3, lines  # one line per kind, however many came
    assert lines[0].startswith("rejected SB_X: finger_width=inf: not a finite number -- dropped")


def test_kinds_have_no_indices_and_what_a_forger_makes_up_cannot_grow_them(caplog):
    r = Rejects("test-receiver")
    with caplog.at_level(logging.WARNING, logger="test-receiver"):
        for i in range(3):
            r.record("SB_ROBOT_OBJECTS", BadValue(f"objects[{i}].pose[{i + 1}]", math.nan, "not a finite number"))
        for i in range(500):  # property keys are the sender's: each a field of its own
            r.record("SB_WM_CHANGES", BadValue(f"ops[0].element.key{i}[0]", math.nan, "not a finite number"))
    assert r.by_kind["SB_ROBOT_OBJECTS: objects[].pose[]"] == 3
    assert len(r.by_kind) == MAX_KINDS + 1 and r.total == 503  # (+ the one for the rest)
    assert r.by_kind["SB_WM_CHANGES: other kinds"] == 500 - (MAX_KINDS - 1)
    assert len(caplog.records) == MAX_KINDS + 1
