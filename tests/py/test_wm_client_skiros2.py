"""The world-model client's questions that conditions ask (has_element, has_relation,
is_instance_of) and SkiROS2's "-1" in get_relations, on a replica filled by hand (no
server: resync is stubbed, and the server queries are recorded and answered here)."""

import pytest

from skillbus.bus import open_bus
from skillbus.world import Element
from skillbus.world.client import WorldModelError, WorldModelInterface


@pytest.fixture
def wmi(monkeypatch):
    monkeypatch.setattr(WorldModelInterface, "resync", lambda self: None)
    w = WorldModelInterface(open_bus("memq://"), "test")
    for eid, etype in (("skiros:Table-1", "skiros:Table"), ("skiros:Cube-2", "skiros:Cube"),
                       ("skiros:Bin-5", "skiros:Bin")):
        w._elements[eid] = Element(etype, "", eid)
    w._add_rel(("skiros:Table-1", "skiros:contain", "skiros:Cube-2"))
    w.asked = []
    w.answer = []

    def query(q):
        w.asked.append(q)
        if isinstance(w.answer, Exception):
            raise w.answer
        return w.answer
    w.query = query
    return w


def test_get_relations_takes_minus_one_as_any(wmi):
    assert wmi.get_relations("-1", "skiros:contain", "skiros:Cube-2") == wmi.get_relations("", "skiros:contain",
                                                                                           "skiros:Cube-2")
    assert [r["src"] for r in wmi.get_relations("-1", "", "skiros:Cube-2")] == ["skiros:Table-1"]
    assert wmi.get_relations("skiros:Table-1", "", "-1")[0]["dst"] == "skiros:Cube-2"


def test_has_relation_answers_from_the_replica_when_it_can(wmi):
    assert wmi.has_relation("skiros:Table-1", "skiros:contain", "skiros:Cube-2")
    assert wmi.has_relation("-1", "skiros:contain", "skiros:Cube-2")
    assert not wmi.has_relation("skiros:Bin-5", "skiros:contain", "skiros:Cube-2")  # nothing between them
    assert wmi.asked == []
    with pytest.raises(ValueError):
        wmi.has_relation("", "skiros:contain", "-1")


def test_has_relation_asks_the_ontology_about_another_predicate(wmi):
    wmi.answer = [Element("skiros:Table", "", "skiros:Table-1")]
    assert wmi.has_relation("skiros:Table-1", "skiros:spatiallyRelated", "skiros:Cube-2")
    q = wmi.asked[-1]
    assert list(q.ids) == ["skiros:Table-1"] and q.ids_only
    assert [(r.subject, r.predicate, r.object) for r in q.relations] == [("", "skiros:spatiallyRelated",
                                                                         "skiros:Cube-2")]
    wmi.answer = []
    assert not wmi.has_relation("", "skiros:on", "skiros:Cube-2")
    q = wmi.asked[-1]
    assert list(q.ids) == ["skiros:Cube-2"] and [(r.subject, r.object) for r in q.relations] == [("*", "")]


def test_is_instance_of_and_has_element(wmi):
    assert wmi.has_element("skiros:Cube-2") and not wmi.has_element("skiros:Cube-9")
    assert wmi.is_instance_of("skiros:Cube-2", "skiros:Cube") and wmi.asked == []
    assert not wmi.is_instance_of("skiros:Cube-9", "skiros:Cube")
    wmi.answer = [Element("skiros:Cube", "", "skiros:Cube-2")]
    assert wmi.is_instance_of("skiros:Cube-2", "skiros:Product")
    assert wmi.asked[-1].type == "skiros:Product" and list(wmi.asked[-1].ids) == ["skiros:Cube-2"]
    wmi.answer = WorldModelError("unknown type 'skiros:Nothing' in query")
    assert not wmi.is_instance_of("skiros:Cube-2", "skiros:Nothing")
