"""What the world-model client hands a reader: copies of the replica's elements that are
made as they are read (Element._reader_copy) yet behave as full copies, and the
relations of an element kept sorted as they change (no sort of 10,000 at every read)."""

from __future__ import annotations

import copy
import pickle

import pytest

from skillbus.bus import open_bus
from skillbus.world import Element
from skillbus.world.client import WorldModelInterface


@pytest.fixture
def wmi(monkeypatch):
    monkeypatch.setattr(WorldModelInterface, "resync", lambda self: None)
    w = WorldModelInterface(open_bus("memq://"), "test")
    cube = Element("skiros:Cube", "red", "skiros:Cube-2")
    cube.setProperty("skiros:Size", [0.05, 0.05, 0.05])
    w._elements = {"skiros:Cube-2": cube, "skiros:Table-1": Element("skiros:Table", "table", "skiros:Table-1")}
    w._add_rel(("skiros:Table-1", "skiros:contain", "skiros:Cube-2"))
    return w


def test_a_reader_copy_is_a_copy(wmi):
    a = wmi.get_element("skiros:Cube-2")
    assert "_properties" not in a.__dict__ and "_relations" not in a.__dict__  # nothing copied yet
    a.getProperty("skiros:Size").setValue(0.1, 0)
    a.addRelation("-1", "skiros:contain", "skiros:Table-1")
    b = wmi.get_element("skiros:Cube-2")
    assert b.getProperty("skiros:Size").values == [0.05, 0.05, 0.05]
    assert b.getRelations() == [{"src": "skiros:Table-1", "type": "skiros:contain", "dst": "skiros:Cube-2",
                                 "state": True, "abstract": False}]
    assert wmi._elements["skiros:Cube-2"].getProperty("skiros:Size").values == [0.05, 0.05, 0.05]
    assert a.changed_since_loaded() and not b.changed_since_loaded()
    assert a.loaded()[2]["skiros:Size"].values == [0.05, 0.05, 0.05]  # what it was read as
    b.label = "blue"
    assert b.changed_since_loaded() and b.loaded()[1] == "red"


def test_get_property_copies_one_property_and_keeps_handing_out_that_one(wmi):
    wmi._elements["skiros:Cube-2"].setProperty("skiros:Mass", 0.2)
    a = wmi.get_element("skiros:Cube-2")
    size = a.getProperty("skiros:Size")
    assert "_properties" not in a.__dict__ and a.getProperty("skiros:Size") is size
    assert a.hasProperty("skiros:Mass", 0.2) and not a.hasProperty("skiros:Nothing")
    size.setValue(0.5, 0)
    assert a.hasProperty("skiros:Size", 0.5)  # what was handed out is the element's
    assert any(p is size for p in a.properties)  # kept when all are copied
    assert a.getProperty("skiros:Size").value == 0.5 and a.changed_since_loaded()
    assert wmi._elements["skiros:Cube-2"].getProperty("skiros:Size").value == 0.05
    with pytest.raises(KeyError):
        wmi.get_element("skiros:Cube-2").getProperty("skiros:Nothing")


def test_a_reader_copy_copies_pickles_and_compares_as_an_element(wmi):
    a = wmi.get_element("skiros:Cube-2")
    for c in (copy.deepcopy(a), pickle.loads(pickle.dumps(a)), a.clone()):
        assert c == a and c is not a
        c.getProperty("skiros:Size").setValue(1.0, 0)
        assert a.getProperty("skiros:Size").value == 0.05
    with pytest.raises(AttributeError):
        a.no_such_attribute  # noqa: B018


def test_relations_stay_sorted_as_they_change(wmi):
    for i in (5, 1, 9, 3):
        wmi._elements[f"skiros:Cube-{i}0"] = Element("skiros:Cube", "", f"skiros:Cube-{i}0")
        wmi._add_rel(("skiros:Table-1", "skiros:contain", f"skiros:Cube-{i}0"))
        if i == 1:
            wmi.get_element("skiros:Table-1")  # the cache is made here, then kept up
    wmi._add_rel(("skiros:Table-1", "skiros:contain", "skiros:Cube-50"))  # twice: once
    wmi._remove_rel(("skiros:Table-1", "skiros:contain", "skiros:Cube-90"))
    wmi._remove_rel(("skiros:Table-1", "skiros:contain", "skiros:Cube-77"))  # not there: nothing
    got = [r["dst"] for r in wmi.get_element("skiros:Table-1").getRelations()]
    assert got == ["skiros:Cube-10", "skiros:Cube-2", "skiros:Cube-30", "skiros:Cube-50"]
    assert got == sorted(r[2] for r in wmi._by_node["skiros:Table-1"])


def test_with_relations_copies_the_callers_element_and_keeps_its_own_relations(wmi):
    mine = Element("skiros:Cube", "red", "skiros:Cube-2")
    mine.setProperty("skiros:Size", 0.07)
    mine.addRelation("-1", "skiros:contain", "skiros:Table-1")
    w = wmi.with_relations(mine)
    mine.getProperty("skiros:Size").setValue(1.0, 0)
    assert w.getProperty("skiros:Size").value == 0.07 and w.loaded()[2]["skiros:Size"].value == 0.07
    rels = {(r["src"], r["type"], r["dst"]) for r in w.getRelations()}
    assert rels == {("-1", "skiros:contain", "skiros:Table-1"), ("skiros:Table-1", "skiros:contain", "skiros:Cube-2")}
    assert not w.changed_since_loaded()


def test_add_relations_completes_the_callers_element_itself(wmi):
    mine = Element("skiros:Cube", "red", "skiros:Cube-2")
    mine.setProperty("skiros:Size", 0.07)
    mine.addRelation("skiros:Table-1", "skiros:contain", "skiros:Cube-2")  # (carried already: not twice)
    assert wmi.add_relations(mine) is mine
    assert mine.getRelations() == [{"src": "skiros:Table-1", "type": "skiros:contain", "dst": "skiros:Cube-2",
                                    "state": True, "abstract": False}]
    assert mine.loaded() is not None and not mine.changed_since_loaded()
    unknown = Element("skiros:Cube", "", "skiros:Cube-99")  # not in the replica: loaded as it is
    assert wmi.add_relations(unknown) is unknown and unknown.getRelations() == [] and unknown.loaded() is not None


def test_a_fresh_element_is_completed_as_one_that_carried_relations_would_be(wmi):
    """A tick's parameter carries no relations: they are the replica's, and what it is
    loaded as is made from those tuples; the same as completing it relation by relation."""
    for eid in ("skiros:Cube-2", "skiros:Table-1"):
        fresh = Element("skiros:Cube", "red", eid)
        fresh.setProperty("skiros:Size", [0.05, 0.06])
        slow = fresh.clone()
        slow._relations = [{"src": "x", "type": "y", "dst": "z", "state": False, "abstract": False}]  # (a false one)
        wmi.add_relations(fresh)
        wmi.add_relations(slow)
        slow._relations = slow._relations[1:]
        assert fresh.getRelations() == slow.getRelations() != []
        assert fresh.loaded()[3] == slow.loaded()[3] == frozenset(fresh._resolved_relations())
        assert fresh.loaded()[:2] == slow.loaded()[:2] and fresh.loaded()[2] == slow.loaded()[2]
        assert fresh.loaded()[2]["skiros:Size"] is not fresh.getProperty("skiros:Size")  # (a copy)
        assert not fresh.changed_since_loaded()
        fresh.getProperty("skiros:Size").setValue(0.5, 0)
        assert fresh.changed_since_loaded()


def hold_skill():
    """A primitive with one element parameter, Object (a tick's parameters are made for it)."""
    from skillbus.skill import ParamTypes, PrimitiveBase, SkillDescription

    class Hold(SkillDescription):
        def createDescription(self):
            self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)

    class hold(PrimitiveBase):
        def createDescription(self):
            self.setDescription(Hold(), "hold")

    return hold


def test_a_ticks_element_parameter_is_completed_once_and_not_copied(wmi, monkeypatch):
    """A tick's element values are made afresh at every tick (skillbus.skill.convert):
    completing them took a copy and remembered what they were loaded as twice. Now each is
    a reader's copy of the decoded element (WorldModelInterface.tick_element): what it was
    loaded as is the decoded element's, never copied nor marked again."""
    from skillbus.skill.convert import apply_param_msgs, param_msg

    hold = hold_skill()
    sender = hold()
    cube = Element("skiros:Cube", "red", "skiros:Cube-2")
    cube.setProperty("skiros:Size", 0.07)
    sender.params["Object"].setValue(cube)
    msgs = [param_msg(sender.params["Object"])]
    skill = hold()
    skill.wmi = wmi
    marks = []
    real_mark = Element.mark_loaded
    monkeypatch.setattr(Element, "mark_loaded", lambda e, **kw: (marks.append(e.id), real_mark(e, **kw))[1])
    monkeypatch.setattr(Element, "clone", lambda e: pytest.fail("a tick's fresh element was copied"))
    apply_param_msgs(skill, msgs)
    got = skill.params["Object"].value
    assert marks == []
    assert got.getProperty("skiros:Size").value == 0.07 and got.loaded()[2]["skiros:Size"].value == 0.07
    assert {(r["src"], r["type"], r["dst"]) for r in got.getRelations()} == {
        ("skiros:Table-1", "skiros:contain", "skiros:Cube-2")}
    assert not got.changed_since_loaded()


def test_without_a_world_model_client_a_ticks_element_is_marked_loaded_as_it_came(monkeypatch):
    from skillbus.skill.convert import apply_param_msgs, param_msg

    hold = hold_skill()
    sender = hold()
    cube = Element("skiros:Cube", "red", "skiros:Cube-2")
    cube.setProperty("skiros:Size", 0.07)
    sender.params["Object"].setValue(cube)
    skill = hold()  # (no wmi: a skill run outside a process)
    monkeypatch.setattr(Element, "clone", lambda e: pytest.fail("a tick's fresh element was copied"))
    apply_param_msgs(skill, [param_msg(sender.params["Object"])])
    got = skill.params["Object"].value
    assert got.loaded() is not None and not got.changed_since_loaded()
    assert got.getProperty("skiros:Size").value == 0.07 and got.loaded()[2]["skiros:Size"].value == 0.07
    assert got.getRelations() == []  # (a tick carries properties only; no replica to add relations)


def test_the_same_ticks_message_is_decoded_once_yet_every_tick_gets_an_element_of_its_own(wmi, monkeypatch):
    """The skill process's tick decoder hands over the same parameter messages while their
    bytes repeat (skillbus.skill.tick_decode): the element is decoded once, and each tick
    gets a new element, the same as a fresh decode, that shares nothing that can change."""
    import skillbus.skill.convert as skill_convert
    import skillbus.world.client as client
    from skillbus.skill.convert import apply_param_msgs, param_msg
    from skillbus.world.convert import element_from_msg

    decodes = []

    def counting(m):
        decodes.append(m.id)
        return element_from_msg(m)

    monkeypatch.setattr(client, "element_from_msg", counting)
    monkeypatch.setattr(skill_convert, "element_from_msg", counting, raising=False)
    hold = hold_skill()
    sender = hold()
    cube = Element("skiros:Cube", "red", "skiros:Cube-2")
    cube.setProperty("skiros:Size", [0.07, 0.08])
    sender.params["Object"].setValue(cube)
    msgs = [param_msg(sender.params["Object"])]
    skill = hold()
    skill.wmi = wmi

    def tick() -> Element:
        apply_param_msgs(skill, msgs)
        return skill.params["Object"].value

    def as_decoded_afresh() -> Element:
        e = element_from_msg(msgs[0].values[0].element)
        return wmi.add_relations(e)

    first = tick()
    first.getProperty("skiros:Size").setValue(9.0, 0)  # what a skill does to its tick's element
    first.addRelation("-1", "skiros:contain", "skiros:Table-1")
    first.label = "changed"
    second = tick()
    assert decodes == ["skiros:Cube-2"], decodes  # once for both ticks
    assert second is not first
    expected = as_decoded_afresh()
    assert second == expected and second.loaded() == expected.loaded() and not second.changed_since_loaded()
    assert second.getRelations() == expected.getRelations() == [
        {"src": "skiros:Table-1", "type": "skiros:contain", "dst": "skiros:Cube-2", "state": True, "abstract": False}]
    assert first.changed_since_loaded() and first.loaded() == expected.loaded()

    # the replica's relations of the element change: the next tick's element has them
    wmi._elements["skiros:Gripper-5"] = Element("skiros:Gripper", "", "skiros:Gripper-5")
    wmi._add_rel(("skiros:Gripper-5", "skiros:contain", "skiros:Cube-2"))
    third = tick()
    assert {r["src"] for r in third.getRelations()} == {"skiros:Table-1", "skiros:Gripper-5"}
    assert third == as_decoded_afresh() and third.loaded() == as_decoded_afresh().loaded()
    # a resync makes the relations anew (resync: new sets and caches): decoded again, the same element
    n = len(decodes)
    wmi._rel_cache = {}
    assert tick() == third and len(decodes) == n + 1
    # the element leaves the replica: as it came, with no relations
    del wmi._elements["skiros:Cube-2"]
    gone = tick()
    assert gone.getRelations() == [] and gone.getProperty("skiros:Size").values == [0.07, 0.08]
    assert not gone.changed_since_loaded()
    # another message with the same bytes (the decoder forgot them, or no decoder): decoded again
    wmi._elements["skiros:Cube-2"] = cube
    msgs = [param_msg(sender.params["Object"])]
    n = len(decodes)
    assert tick() == as_decoded_afresh() and len(decodes) > n
