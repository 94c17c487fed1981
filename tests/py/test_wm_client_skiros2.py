"""The world-model client's questions that conditions ask (has_element, has_relation,
is_instance_of) and SkiROS2's "-1" in get_relations, on a replica filled by hand (no
server: resync is stubbed, the server's hierarchy is given here, and every other question
to the server fails the test: these are answered from the replica)."""

import pytest

from skillbus.bus import open_bus
from skillbus.world import Element
from skillbus.world.client import WorldModelInterface
from skillbus.world.ontology_view import OntologyView

HIERARCHY = {"classes": {"skiros:Product": [], "skiros:Cube": ["skiros:Product"], "skiros:Table": [],
                         "skiros:Bin": []},
             "relations": {"skiros:spatiallyRelated": [], "skiros:contain": ["skiros:spatiallyRelated"],
                           "skiros:on": []}}


@pytest.fixture
def wmi(monkeypatch):
    monkeypatch.setattr(WorldModelInterface, "resync", lambda self: None)
    w = WorldModelInterface(open_bus("memq://"), "test")
    for eid, etype in (("skiros:Table-1", "skiros:Table"), ("skiros:Cube-2", "skiros:Cube"),
                       ("skiros:Bin-5", "skiros:Bin")):
        w._elements[eid] = Element(etype, "", eid)
    w._add_rel(("skiros:Table-1", "skiros:contain", "skiros:Cube-2"))
    w._ontology_cache = OntologyView.from_json(HIERARCHY)
    w.asked = []
    w.query = w._call = lambda *a, **k: pytest.fail(f"asked the server {a}")
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


def test_has_relation_counts_subproperties_by_the_servers_hierarchy(wmi):
    assert wmi.has_relation("skiros:Table-1", "skiros:spatiallyRelated", "skiros:Cube-2")
    assert wmi.has_relation("-1", "skiros:spatiallyRelated", "skiros:Cube-2")
    assert not wmi.has_relation("", "skiros:on", "skiros:Cube-2")
    assert not wmi.has_relation("skiros:Table-1", "skiros:unknownRelation", "skiros:Cube-2")


def test_is_instance_of_and_has_element(wmi):
    assert wmi.has_element("skiros:Cube-2") and not wmi.has_element("skiros:Cube-9")
    assert wmi.is_instance_of("skiros:Cube-2", "skiros:Cube")
    assert not wmi.is_instance_of("skiros:Cube-9", "skiros:Cube")
    assert wmi.is_instance_of("skiros:Cube-2", "skiros:Product")
    assert not wmi.is_instance_of("skiros:Table-1", "skiros:Product")
    assert not wmi.is_instance_of("skiros:Cube-2", "skiros:Nothing")
