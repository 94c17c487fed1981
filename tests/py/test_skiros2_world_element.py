"""SkiROS2's world element tests (skiros2_common/src/test/test_world_element.py), case by
case, on skillbus.world.Element; then the rest of the Element / Property API skillbus took
over from SkiROS2 (the "-1" convention, data codes, isInstance)."""

import logging
import math

import pytest
from world_standin import WorldStandIn

# SkiROS2: from skiros2_common.core.world_element import Element
from skillbus.world import Element, Property
from skillbus.world.element_data import Header, Pose, PoseStamped, Stamp


def rel(subj, pred, obj, state=True, abstract=False) -> dict:
    """A relation as an element stores it (state and abstract at their defaults)."""
    return {"src": subj, "type": pred, "dst": obj, "state": state, "abstract": abstract}


# ---- the upstream cases -----------------------------------------------------------------------
def test_element():
    e = Element()
    e.setProperty("Hello", float)
    e.setProperty("Hello", 0.0)
    assert e.getProperty("Hello").value == 0.0
    e.getProperty("Hello").values = 1.0
    assert e.getProperty("Hello").values == [1.0]
    e.getProperty("Hello").value = 2.0
    assert e.getProperty("Hello").values == [2.0]


def test_getIdNumber():
    e = Element()
    assert e.getIdNumber() == -1  # no id yet
    e.setUri(4)
    assert e.getIdNumber() == 4


def test_getRelations():
    e = Element()
    e.addRelation("1", "pred1", "2")
    e.addRelation("-1", "pred2", "3")
    assert e.getRelations() == [rel("1", "pred1", "2"), rel("-1", "pred2", "3")]  # no filter: all, in order
    assert e.getRelations("1", "pred1", "2") == [rel("1", "pred1", "2")]


def test_setRelation():
    e = Element()
    e.addRelation("-1", "pred", "2")
    e.addRelation("1", "pred", "2")
    # with "-1" as subject, only the element's own relations of that predicate are replaced
    e.setRelation("-1", "pred", "3")
    assert e.getRelations() == [rel("1", "pred", "2"), rel("-1", "pred", "3")]
    # with neither end "-1", every relation of the predicate is replaced
    e.setRelation("1", "pred", "2")
    assert e.getRelations() == [rel("1", "pred", "2")]


def test_addRelation():
    e = Element()
    e.addRelation("1", "pred", "2")
    e.addRelation("1", "pred", "2")  # already there: stored once
    assert e.getRelations() == [rel("1", "pred", "2")]
    # Upstream checks Python 2 unicode strings here; in Python 3 u"2" is a str.
    e.addRelation(u"2", "pred", u"3")
    assert e.getRelations() == [rel("1", "pred", "2"), rel("2", "pred", "3")]


def test_hasProperty():
    e = Element()
    e.setProperty("Integer", "2", "xsd:int")
    assert not e.hasProperty("NonExistingKey")
    assert not e.hasProperty("Integer", 1)
    # Upstream fails this one: its setProperty leaves the property empty when the text
    # is not already an int. skillbus converts to the datatype given.
    assert e.hasProperty("Integer", 2)
    assert e.hasProperty("Integer")
    e.setProperty("Type", int)
    assert not e.hasProperty("Type", not_none=True)


def test_setProperty():
    e = Element()
    e.setProperty("Integer", 1)
    assert e.getProperty("Integer").values == [1]
    e.setProperty("Integer", "2", force_convertion=True)  # converted to the property's type
    assert e.getProperty("Integer").values == [2]
    e.setProperty("Integer", ["1", "2"], force_convertion=True)  # each value of a list
    assert e.getProperty("Integer").values == [1, 2]
    # Upstream: Python 2 unicode becomes str; in Python 3 they are one type.
    e.setProperty("strKey", u"a")
    assert type(e.getProperty("strKey").value) is str
    e.setProperty("strKey", u"b")
    assert e.getProperty("strKey").values == ["b"]


def test_appendProperty():
    e = Element()
    e.setProperty("Integer", 2, "xsd:int")
    assert e.getProperty("Integer").value == 2
    e.appendProperty("Integer", 3)
    assert e.getProperty("Integer").values == [2, 3]


# ---- beyond the upstream tests --------------------------------------------------------------
def test_own_relations_under_minus_one_or_the_id():
    # SkiROS2 code finds an element's own relations with subj="-1"; an element read from
    # the skillbus world model carries its id there instead. Either form finds either.
    e = Element("skiros:Table", "", "skiros:Table-1")
    e.addRelation("skiros:Table-1", "skiros:contain", "skiros:Cube-2")   # as the world model gives it
    e.addRelation("-1", "skiros:contain", "skiros:Cube-3")               # as SkiROS2 code writes it
    e.addRelation("skiros:Scene-0", "skiros:contain", "-1")
    assert [r["dst"] for r in e.getRelations(subj="-1", pred="skiros:contain")] == ["skiros:Cube-2", "skiros:Cube-3"]
    assert len(e.getRelations(subj="skiros:Table-1", pred="skiros:contain")) == 2
    assert e.getRelation(pred="skiros:contain", obj="-1")["src"] == "skiros:Scene-0"
    assert e.getRelation(pred="skiros:contain", obj="skiros:Table-1")["src"] == "skiros:Scene-0"
    assert e.getRelations(subj="skiros:Cube-2") == []
    # an abstract element: only "-1" is the element
    a = Element("skiros:Table")
    a.addRelation("-1", "p", "x")
    assert a.getRelations(subj="-1") == [rel("-1", "p", "x")] and a.getRelations(subj="") == [rel("-1", "p", "x")]


def test_removeRelation2(caplog):
    e = Element("skiros:Table", "", "skiros:Table-1")
    e.addRelation("skiros:Table-1", "skiros:contain", "skiros:Cube-2")
    e.addRelation("-1", "skiros:at", "skiros:Room-4", False)
    e.removeRelation2("-1", "skiros:contain", "skiros:Cube-2")  # "-1" finds the id form
    e.removeRelation2("-1", "skiros:at", "skiros:Room-4", value=False)
    assert e.getRelations() == []
    with caplog.at_level(logging.ERROR, logger="skillbus.world"):
        e.removeRelation2("-1", "skiros:at", "skiros:Room-4")  # not there: an error is logged, nothing raised
    assert "has no relation" in caplog.text


def test_print_state_id_number_and_available_properties():
    e = Element("skiros:Cube", "red", "skiros:Cube-12")
    e.setProperty("skiros:Size", 0.05)
    assert e.printState() == "skiros:Cube-12-red" and Element().printState() == "Unknown-"
    assert e.printState(True) == "skiros:Cube-12-red\nskiros:Size:[0.05]"
    assert e.getIdNumber() == 12 and Element("a", "", "a:b-c-2").getIdNumber() == 2
    assert list(e.available_properties) == ["skiros:Size"]


def test_data_codes_without_ros():
    e = Element("skiros:Cube", "c", "skiros:Cube-2")
    assert not e.hasData(":Pose") and e.getData(":Position") == [None, None, None]
    e.setData(":Position", [1, 2, 3])  # ints become floats (SkiROS2 drops them, logging an error)
    e.setData(":Orientation", [0.0, 0.0, 0.0, 1.0])
    assert e.getData(":Position") == [1.0, 2.0, 3.0] and e.hasData(":Pose") and e.hasData(":Position")
    assert e.getData(":Pose") == ([1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0])
    pose = e.getData(":PoseMsg")  # SkiROS2: geometry_msgs/Pose; here a named tuple with its fields
    assert isinstance(pose, tuple) and pose.position.x == 1.0 and pose.orientation.w == 1.0
    position, orientation = pose
    assert tuple(position) == (1.0, 2.0, 3.0)
    e.setData(":PoseStampedMsg", PoseStamped(Header("skiros:Table-1", Stamp(12.5)), Pose((0.5, 0, 0), (0, 0, 0, 1))))
    stamped = e.getData(":PoseStampedMsg")
    assert stamped.header.frame_id == "skiros:Table-1" and stamped.header.stamp.to_sec() == 12.5
    assert stamped.pose.position == (0.5, 0.0, 0.0)
    tf = e.getData(":TransformMsg")
    assert tf.child_frame_id == "skiros:Cube-2" and tf.transform.translation.x == 0.5
    e.setData(":Size", (0.1, 0.2, 0.3))
    assert e.getData(":Size") == [0.1, 0.2, 0.3] and e.hasData(":Size")
    e.setData(":OrientationEuler", [0.1, -0.2, 0.3])
    assert [round(a, 9) for a in e.getData(":OrientationEuler")] == [0.1, -0.2, 0.3]
    assert math.isclose(sum(c * c for c in e.getData(":Orientation")), 1.0)
    with pytest.raises(KeyError, match="no data code ':pX'"):  # SkiROS2's relation codes are not here
        e.getData(":pX")


def test_property_api():
    p = Property("k", [1, 2, 3, 1, -1])
    p.setValue(13, -1)
    assert p.values == [1, 2, 3, 1, 13] and p.find(1) == 0 and p.find(99) == -1 and p.isList()
    p.removeValue(1)
    assert p.values == [2, 3, 1, 13]
    p.unset()
    assert p.value is None and not p.isSpecified()
    p.setValue(1, 0)
    assert p.values == [1]
    p.setValues(None)
    assert p.values == []
    f = Property("f", float)
    f.setValueFromStr("2.5")
    f.setValuesFromStr("1;2")
    assert f.values == [1.0, 2.0] and f.getValuesStr() == "1.0;2.0" and f.dataTypeIs(float) and f.dataTypeIs(3.0)


def test_isInstance():
    world = WorldStandIn(superclasses={"skiros:Cube": "skiros:Product"})
    table = world.add("skiros:Table", "table")
    cube = world.add("skiros:Cube", "red", skiros_Size=0.05)
    world.set_relation(table.id, "skiros:contain", cube.id)
    cube = world.get_element(cube.id)

    wanted = Element("skiros:Product")
    assert cube.isInstance(wanted, world)                   # a subclass
    assert not table.isInstance(wanted, world)
    wanted.setProperty("skiros:Size", 0.05)
    assert cube.isInstance(wanted, world)
    wanted.label = "blue"
    assert not cube.isInstance(wanted, world)
    wanted.label = "Unknown"                                # no label wanted
    wanted.addRelation("skiros:Thing", "skiros:contain", "-1")  # contained by something
    assert cube.isInstance(wanted, world)
    inside = Element("skiros:Product")
    inside.addRelation("-1", "skiros:contain", "skiros:Thing")  # contains something
    assert not cube.isInstance(inside, world)
