"""Element and Property follow SkiROS2's API (skiros2_common.core.world_element)."""

import pytest

from skillbus.msgs import wm_value_t
from skillbus.world import Element
from skillbus.world.convert import element_from_msg, element_msg, value_msg


def test_properties_like_skiros2():
    e = Element("skiros:Cube", "red")
    e.setProperty("Hello", float)
    assert e.hasProperty("Hello") and not e.hasProperty("Hello", not_none=True)
    e.setProperty("Hello", 0.0)
    assert e.getProperty("Hello").value == 0.0
    e.getProperty("Hello").values = 1.0
    assert e.getProperty("Hello").values == [1.0]
    e.setProperty("Integer", "2", "xsd:int")
    assert e.getProperty("Integer").value == 2
    e.appendProperty("Integer", 3)
    assert e.getProperty("Integer").values == [2, 3]
    assert e.hasProperty("Integer", 3)
    e.removeProperty("Integer")
    assert not e.hasProperty("Integer")
    with pytest.raises(KeyError, match="has no property Nope"):
        e.getProperty("Nope")
    with pytest.raises(ValueError, match="datatype xsd:color"):
        e.setProperty("c", 1, "xsd:color")


def test_identity():
    e = Element("skiros:Cube", "red")
    assert e.isAbstract() and e.getIdNumber() == -1
    e.setUri(7)
    assert e.id == "skiros:Cube-7" and e.getIdNumber() == 7 and not e.isAbstract()
    assert e.printState() == "skiros:Cube-7-red"


def test_relations_like_skiros2():
    e = Element("skiros:Cube", "", "skiros:Cube-2")
    e.addRelation("skiros:Table-1", "skiros:contain", "-1")
    e.addRelation("skiros:Table-1", "skiros:contain", "-1")  # no duplicates
    assert e.getRelations() == [{"src": "skiros:Table-1", "type": "skiros:contain", "dst": "-1",
                                 "state": True, "abstract": False}]
    assert e.hasRelation("skiros:Table-1", "skiros:contain", "-1")
    assert e.hasRelation("skiros:Table-1", "skiros:contain", "skiros:Cube-2")  # -1 is the element
    e.setRelation("skiros:Bin-5", "skiros:contain", "-1")
    assert [r["src"] for r in e.getRelations(pred="skiros:contain")] == ["skiros:Bin-5"]
    with pytest.raises(ValueError, match="must be ids"):
        e.addRelation(1, "skiros:at", "x")


def test_message_round_trip_keeps_value_types():
    e = Element("skiros:Cube", "c", "skiros:Cube-1")
    e.setProperty("s", "text")
    e.setProperty("i", 3)
    e.setProperty("f", 0.25)
    e.setProperty("b", True)
    e.setProperty("many", [1.0, 2.0])
    back = element_from_msg(type(element_msg(e)).decode(element_msg(e).encode()))
    assert back == e
    assert type(back.getProperty("b").value) is bool and type(back.getProperty("i").value) is int
    assert value_msg(True, "b").type == wm_value_t.BOOL  # bool is not taken for an int
    with pytest.raises(TypeError, match="property x: a value of type dict"):
        value_msg({}, "x")


def test_an_element_off_the_wire_is_what_set_property_makes():
    # element_from_msg builds without setProperty (a parameter at every tick): the same
    # element, a key given twice keeping its last values, an empty property, and an
    # unknown value type refused as before.
    from skillbus.msgs import wm_element_t, wm_property_t

    def prop(key, *values):
        p = wm_property_t()
        p.key = key
        p.values = [value_msg(v, key) for v in values]
        p.num_values = len(p.values)
        return p

    m = wm_element_t()
    m.id, m.type, m.label = "skiros:Cube-2", "skiros:Cube", "red"
    m.properties = [prop("s", "a", "b"), prop("i", 3), prop("f", 0.5, 1.5), prop("b", False), prop("empty"),
                    prop("i", 4, 5)]
    m.num_properties = len(m.properties)
    by_hand = Element("skiros:Cube", "red", "skiros:Cube-2")
    for p in m.properties:
        by_hand.setProperty(p.key, [v.s if v.type == wm_value_t.STRING else v.i if v.type == wm_value_t.INT else
                                    v.f if v.type == wm_value_t.FLOAT else v.b for v in p.values])
    got = element_from_msg(type(m).decode(m.encode()))
    assert got == by_hand
    assert got.getProperty("i").values == [4, 5] and got.getProperty("empty").values == []
    assert got.getProperty("f").dataType() is float and got.getProperty("empty").dataType() is None
    assert got.getRelations() == [] and got.loaded() is None and not got.isAbstract()
    # A key given twice with another type, or empty the second time: setProperty's rules
    # (the first values' type stays), as before.
    for first, again in ((prop("k", 1.5), prop("k", "x")), (prop("e", 2), prop("e"))):
        m2 = wm_element_t()
        m2.id, m2.type, m2.label = "skiros:Cube-3", "skiros:Cube", "green"
        m2.properties = [first, again]
        m2.num_properties = 2
        by_hand = Element("skiros:Cube", "green", "skiros:Cube-3")
        for p in m2.properties:
            by_hand.setProperty(p.key, [v.s if v.type == wm_value_t.STRING else v.i if v.type == wm_value_t.INT else
                                        v.f for v in p.values])
        got = element_from_msg(m2)
        assert got == by_hand
        assert got.getProperty(first.key).dataType() is by_hand.getProperty(first.key).dataType() is not None
    m.properties[1].values[0].type = 99
    with pytest.raises(KeyError):
        element_from_msg(m)
