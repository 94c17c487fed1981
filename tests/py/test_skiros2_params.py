"""SkiROS2's parameter tests (skiros2_common/src/test/test_params.py), case by case, on
skillbus.skill.params; then the rest of the Param / ParamHandler API skillbus took over
from SkiROS2, and where it deliberately differs."""

import copy
import logging

import pytest

# SkiROS2: import skiros2_common.core.params as params; skiros2_common.core.world_element
from skillbus.skill.params import Element, Param, ParamHandler, ParamTypes


def values_by_key(ph_or_map) -> dict:
    """Each parameter's values, by key (from a handler or from a map such as merge gives)."""
    items = ph_or_map.items()
    return {k: p.values for k, p in items}


@pytest.fixture
def handlers():
    first, second = ParamHandler(), ParamHandler()
    first.addParam("a", 1, ParamTypes.Required)
    second.addParam("b", 2, ParamTypes.Required)
    assert values_by_key(first) == {"a": [1]}  # addParam stores the key with its value
    return first, second


# ---- the upstream cases: ParamHandler ------------------------------------------------------------
def test_merge(handlers):
    first, second = handlers
    # both keys, each from the handler that has it
    assert values_by_key(first.merge(second)) == {"a": [1], "b": [2]}
    # a key both have: the other handler's value wins
    first.addParam("c", 1, ParamTypes.Required)
    second.addParam("c", 3, ParamTypes.Required)
    assert values_by_key(first.merge(second)) == {"a": [1], "b": [2], "c": [3]}
    # a key the other handler has without a value is dropped
    first.addParam("b", 1, ParamTypes.Required)
    second.addParam("a", float, ParamTypes.Required)
    assert values_by_key(first.merge(second)) == {"b": [2], "c": [3]}


def test_specify(handlers):
    ph, _ = handlers
    ph.addParam("a", dict, ParamTypes.Required)  # replaces the set-up's "a"
    ph.specify("b", {"c": 1})  # no such key: nothing happens (an error is logged)
    assert values_by_key(ph) == {"a": []}
    ph.specify("a", {"MyTraj": "Ue"})
    assert values_by_key(ph) == {"a": [{"MyTraj": "Ue"}]}


def test_remap(handlers):
    ph, _ = handlers
    ph.remap("a", "b")
    assert values_by_key(ph) == {"b": [1]}
    ph.remap("b", "b")  # onto itself: no change
    assert values_by_key(ph) == {"b": [1]}


def test_specifyParams(handlers):
    first, second = handlers
    first.specifyParams(second)  # no key in common: nothing changes
    assert values_by_key(first) == {"a": [1]}
    second.addParam("a", 2, ParamTypes.Required)
    first.specifyParams(second)  # the shared key takes the other's value
    assert values_by_key(first) == {"a": [2]}


def test_specifyParamsDefault(handlers):
    first, second = handlers
    first.specifyParamsDefault(second)
    assert values_by_key(first) == {"a": [1]}
    second.addParam("a", 2, ParamTypes.Required)
    first.specifyParamsDefault(second)
    assert values_by_key(first) == {"a": [2]}
    first.setDefault("a")  # ... and it is the default now
    assert values_by_key(first) == {"a": [2]}


def test_setDefault(handlers):
    ph, _ = handlers
    ph.addParam("b", int, ParamTypes.Required)
    ph.specify("a", 2)
    ph.specify("b", 2)
    ph.setDefault("a")  # one key
    assert values_by_key(ph) == {"a": [1], "b": [2]}
    ph.specify("a", 2)
    ph.setDefault(["a"])  # a list of keys
    assert values_by_key(ph) == {"a": [1], "b": [2]}
    ph.specify("a", 2)
    ph.setDefault()  # every key; "b" had no default
    assert values_by_key(ph) == {"a": [1], "b": []}


def test_getParamValue(handlers):
    ph, _ = handlers
    ph.addParam("a", int, ParamTypes.Required)
    assert ph.getParamValue("b") is None  # no such key
    ph.specify("a", [1, 2])
    assert ph.getParamValue("a") == 1  # the first of the values


def test_getParamValues(handlers):
    ph, _ = handlers
    ph.addParam("a", int, ParamTypes.Required)
    ph.addParam("b", [1.1, 2.0], ParamTypes.Required)
    assert ph.getParamValues("a") == []  # no value yet
    assert ph.getParamValues("b") == [1.1, 2.0]  # a list given to addParam is the values


def test_getElementParams(handlers):
    ph, _ = handlers
    e1, e2 = Element("Type1"), Element("Type2")
    ph.addParam("e1", e1, ParamTypes.Optional)
    ph.addParam("e2", e2, ParamTypes.Optional)
    found = {k: p.value for k, p in ph.getElementParams().items()}
    assert found == {"e1": e1, "e2": e2}
    assert found["e1"] is e1 and found["e2"] is e2  # the very objects given


def test_getParamMapFiltered(handlers):
    ph, _ = handlers
    ph.addParam("b", "hello", ParamTypes.Optional)
    ph.addParam("c", 1.1, ParamTypes.Inferred)
    assert values_by_key(ph.getParamMapFiltered(ParamTypes.Required)) == {"a": [1]}
    assert values_by_key(ph.getParamMapFiltered([ParamTypes.Inferred, ParamTypes.Optional])) == {
        "b": ["hello"], "c": [1.1]}


# ---- the upstream cases: Param --------------------------------------------------------------------
def test_param_hasChanges():
    p = Param("MyProp", "", 0, ParamTypes.Required)
    assert p.value == 0
    since = p.last_update
    assert not p.hasChanges(since)
    p.value = 1
    # Upstream this depends on the clock moving more than 1 µs between the two lines;
    # here a change is always dated at least 2 µs after the previous one.
    assert p.hasChanges(since)


def test_param_toElement():
    e = Param("MyProp", "", 0, ParamTypes.Required).toElement()
    assert e.getProperty("skiros:DataType").dataType() is int
    assert e.getProperty("skiros:Default").values == [0]
    assert e.getProperty("skiros:Value").values == [0]

    e = Param("MyElement", "", Element("MyType", eid="1"), ParamTypes.Required).toElement()
    assert e.getProperty("skiros:DataType").values == ["MyType"]
    assert e.getRelation("-1", "skiros:hasValue", "1") == {
        "src": "-1", "dst": "1", "type": "skiros:hasValue", "state": True, "abstract": False}


# ---- beyond the upstream tests: the rest of SkiROS2's API ----------------------------------------
def test_a_missing_key_logs_an_error_and_gives_none(caplog):
    ph = ParamHandler()
    ph.addParam("a", 1, ParamTypes.Required)
    with caplog.at_level(logging.ERROR, logger="skillbus.params"):
        assert ph["x"] is None and ph.getParam("x") is None
        assert ph.getParamValue("x") is None and ph.getParamValues("x") is None
        ph.specify("x", 1)
        ph.specifyDefault("x", 1)
    assert len(caplog.records) == 6 and all("'x' is not in the map" in r.getMessage() for r in caplog.records)
    with pytest.raises(KeyError):  # as in SkiROS2: these two raise
        ph.isSpecified("x")
    with pytest.raises(KeyError):
        ph.setDefault("x")


def test_keys_values_items_reset_and_print_state():
    ph = ParamHandler()
    ph.addParam("n", 1, ParamTypes.Required)
    ph.addParam("e", Element("skiros:Cube", "cube", "skiros:Cube-3"), ParamTypes.Optional)
    ph.addParam("t", dict, ParamTypes.Optional, "a description given fourth, as SkiROS2's handler takes it")
    assert list(ph.keys()) == ["n", "e", "t"] and [p.key for p in ph.values()] == ["n", "e", "t"]
    assert ph["t"].description.startswith("a description") and ph["t"].options == []
    assert ph.printState() == "n:[1] e: skiros:Cube-3-cube t:[] "
    other = ParamHandler({"z": Param("z", "", 5, ParamTypes.Optional)})
    ph.reset(other.getCopy())
    assert values_by_key(ph) == {"z": [5]}


def test_copies_are_real_copies():
    # SkiROS2's getCopy and deepcopy share the value lists with the original; skillbus copies.
    ph = ParamHandler()
    ph.addParam("a", [1, 2], ParamTypes.Required)
    ph.addParam("e", Element("skiros:Cube"), ParamTypes.Required)
    for c in (ph.getCopy(), copy.deepcopy(ph).getParamMap()):
        c["a"].setValue(5)
        c["a"].addValue(6)
        c["e"].value.label = "changed"
    assert ph.getParamValues("a") == [1, 2] and ph["e"].value.label == ""


def test_a_copy_is_what_a_generic_deep_copy_is_and_shares_nothing_that_changes():
    # Param.copy (every start of a primitive copies its description's parameters) against
    # copy.deepcopy's own walk of the object (Param.__deepcopy__ bypassed).
    cube = Element("skiros:Cube", "cube", "skiros:Cube-3")
    cube.setProperty("skiros:Size", [0.05, 0.05, 0.05])
    cube.addRelation("-1", "skiros:contain", "skiros:Bin-1")
    made = [Param("n", "count", 1, ParamTypes.Required),
            Param("via", "", [[0.1, 0.2], [0.3]], ParamTypes.Optional),
            Param("cfg", "", {"a": [1, 2]}, ParamTypes.Optional),
            Param("obj", "", cube, ParamTypes.Inferred, options=[[1, 2]]),
            Param("none", "", float, ParamTypes.Optional)]
    made[0].setValue(4)  # values apart from the default
    for p in made:
        generic = copy.copy(p)
        generic.__dict__ = copy.deepcopy(p.__dict__)
        c = p.copy()
        assert type(c) is Param and c.__dict__.keys() == generic.__dict__.keys()
        assert (c.key, c.description, c.paramType, c.dataType(), c.last_update) == \
            (generic.key, generic.description, generic.paramType, generic.dataType(), generic.last_update)
        assert c.values == generic.values and c.defaults == generic.defaults and c.options == generic.options
        assert copy.deepcopy(p).values == c.values
    obj = made[3].copy()
    obj.value.setProperty("skiros:Size", [1.0])
    obj.value.addRelation("-1", "skiros:at", "skiros:Table-1")
    obj.defaults[0].label = "other"
    obj.options[0].append(3)
    assert cube.getProperty("skiros:Size").values == [0.05, 0.05, 0.05] and len(cube.getRelations()) == 1
    assert made[3].default.label == "cube" and made[3].options == [[1, 2]]
    via = made[1].copy()
    via.values[0].append(9.9)
    cfg = made[2].copy()
    cfg.value["a"].append(3)
    assert made[1].values == [[0.1, 0.2], [0.3]] and made[2].value == {"a": [1, 2]}


def test_specifyParams_keep_default():
    target = ParamHandler()
    target.addParam("n", 1, ParamTypes.Required)                                   # a default: kept
    target.addParam("free", int, ParamTypes.Optional)                              # none: takes the value
    target.addParam("abstract", Element("skiros:Cube"), ParamTypes.Required)       # abstract default: takes it
    target.addParam("same", Element("skiros:Cube", "", "skiros:Cube-2"), ParamTypes.Required)
    target.addParam("other", Element("skiros:Cube", "", "skiros:Cube-2"), ParamTypes.Required)
    given = ParamHandler()
    given.addParam("n", 7, ParamTypes.Required)
    given.addParam("free", 7, ParamTypes.Required)
    given.addParam("abstract", Element("skiros:Cube", "c", "skiros:Cube-4"), ParamTypes.Required)
    given.addParam("same", Element("skiros:Cube", "fresh", "skiros:Cube-2"), ParamTypes.Required)
    given.addParam("other", Element("skiros:Cube", "", "skiros:Cube-9"), ParamTypes.Required)
    target.specifyParams(given, keep_default=True)
    assert target.getParamValue("n") == 1 and target.getParamValue("free") == 7
    assert target.getParamValue("abstract").id == "skiros:Cube-4"
    assert target.getParamValue("same").label == "fresh"  # the same element, updated
    assert target.getParamValue("other").id == "skiros:Cube-2"


def test_param_values_api():
    p = Param("k", "", [1, 2, 3, 1], ParamTypes.Required)
    assert p.isList() and p.find(1) == 0 and p.find(9) == -1 and p.getValuesStr() == "1;2;3;1"
    p.setValue(13, -1)  # a negative index replaces from the end
    p.setValue(14, 99)  # past the end: appended
    assert p.values == [1, 2, 3, 13, 14]
    p.removeValue(2)
    p.removeValue(42)  # not there: nothing
    p.addValue(7)
    assert p.values == [1, 3, 13, 14, 7]
    p.setValues([4])
    assert p.values == [4] and not p.isList()
    p.unset()
    assert p.value is None and not p.isSpecified() and p.values == []
    p.setValuesFromStr("5;6")
    assert p.values == [5, 6] and p.printState() == "k:[5, 6]"
    d = Param("d", "", dict, ParamTypes.Optional)
    d.setValueFromStr("{'a': 1}")
    assert d.value == {"a": 1}
    with pytest.raises(TypeError, match="parameter k holds int, not str"):  # SkiROS2 logs and ignores
        p.addValue("x")
    long = Param("long", "", "x" * 600, ParamTypes.Optional)
    assert long.printState().endswith(" ...]") and len(long.printState()) == len("long:") + 500 + 5


def test_param_defaults_and_types():
    p = Param("speed", "how fast", 0.5, ParamTypes.Optional)
    assert p.hasSpecifiedDefault() and p.default == 0.5 and p.defaults == [0.5] and p.hasDefaultValues()
    assert p.paramTypeIs(ParamTypes.Optional) and not p.paramTypeIs(ParamTypes.Required)
    assert p.dataTypeIs(float) and p.dataTypeIs(2.0) and not p.dataTypeIs(int)
    p.value = 0.7
    assert not p.hasDefaultValues()
    before = p.last_update
    p.setDefault()  # back to the default; not a change of last_update (as in SkiROS2)
    assert p.value == 0.5 and p.last_update == before
    p.makeDefault(0.9)
    p.value = 0.1
    p.setDefault()
    assert p.value == 0.9
    t = Param("t", "", float, ParamTypes.Optional)
    assert not t.hasSpecifiedDefault() and t.getDefaultValue() is None and t.makeInstance() == 0.0
    assert Param("n", "", 0, 1).paramType == ParamTypes.Optional  # an int kind counts from 0, as SkiROS2 reads it
    with pytest.raises(ValueError, match="same type"):
        Param("mixed", "", [1, "a"], ParamTypes.Required)
    with pytest.raises(ValueError, match="empty list"):
        Param("empty", "", [], ParamTypes.Required)


def test_a_list_typed_parameter_holds_lists():
    p = Param("waypoints", "", list, ParamTypes.Optional)
    p.values = [1, 2]          # not lists: one value
    assert p.values == [[1, 2]]
    p.values = [[1], [2, 3]]   # lists: the values
    assert p.values == [[1], [2, 3]]
    p.values = []              # clears
    assert p.values == []


def test_last_update_follows_every_change():
    p = Param("k", "", 1, ParamTypes.Required)
    stamps = [p.last_update]
    for change in (lambda: p.setValue(2), lambda: p.setValues([3]), lambda: p.addValue(4),
                   lambda: p.removeValue(4), lambda: p.unset()):
        change()
        assert p.hasChanges(stamps[-1])
        stamps.append(p.last_update)
    assert stamps == sorted(stamps) and len(set(stamps)) == len(stamps)
