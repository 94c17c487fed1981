"""SkiROS2's ontology and world questions on the world-model client (get_sub_properties,
get_sub_classes, get_individuals, get_type(s), get_triples, get_branch, check_relation,
instanciate, what raises NotImplementedError), and set_relation after the world was
replaced behind the replica's back. No server: the replica is filled by hand, the
server's answers (query, commit, its version, a resync) are played here."""

from __future__ import annotations

import pytest

from skillbus.bus import open_bus
from skillbus.msgs import wm_change_t, wm_op_t
from skillbus.world import Element
from skillbus.world.client import WorldModelError, WorldModelInterface

SUBPROPERTIES = {("skiros:contain", "skiros:spatiallyRelated"), ("skiros:at", "skiros:spatiallyRelated")}
SUBCLASSES = {("skiros:Cube", "skiros:Product"), ("skiros:Cube", "skiros:PhysicalObject"),
              ("skiros:Table", "skiros:Location"), ("skiros:Bin", "skiros:Location"),
              ("skiros:Table", "skiros:PhysicalObject"), ("skiros:Bin", "skiros:PhysicalObject"),
              ("skiros:Product", "skiros:PhysicalObject"), ("skiros:Location", "skiros:PhysicalObject"),
              ("skiros:Gripper", "skiros:PhysicalObject")}
CONCEPTS = {c for pair in SUBCLASSES for c in pair}


class Server:
    """The world model server as the client sees it: a world, a version, its ontology."""

    def __init__(self):
        self.elements = {eid: Element(t, label, eid) for eid, t, label in (
            ("skiros:Table-1", "skiros:Table", "table"), ("skiros:Cube-2", "skiros:Cube", "red"),
            ("skiros:Cube-3", "skiros:Cube", "green"), ("skiros:Bin-5", "skiros:Bin", "bin"),
            ("skiros:Gripper-7", "skiros:Gripper", ""))}
        self.elements["skiros:Cube-2"].setProperty("skiros:Weight", 0.2)
        self.relations = {("skiros:Table-1", "skiros:contain", "skiros:Cube-2"),
                          ("skiros:Table-1", "skiros:contain", "skiros:Cube-3"),
                          ("skiros:Gripper-7", "skiros:at", "skiros:Table-1"),
                          ("skiros:Table-1", "skiros:hasTemplate", "skiros:Bin-5")}
        self.version = 3
        self.commits: list[list[tuple]] = []

    def is_sub(self, pred, ancestor):
        return pred == ancestor or (pred, ancestor) in SUBPROPERTIES

    def is_subclass(self, c, ancestor):
        return c == ancestor or (c, ancestor) in SUBCLASSES

    def query(self, q):
        if q.type and q.type not in CONCEPTS:
            raise WorldModelError(f"unknown type '{q.type}' in query")
        out = []
        for eid, e in sorted(self.elements.items()):
            if q.ids and eid not in q.ids:
                continue
            if q.type and not (e.type == q.type if q.exact_type else self.is_subclass(e.type, q.type)):
                continue
            ok = True
            for pat in q.relations:
                s = eid if pat.subject == "" else pat.subject
                o = eid if pat.object == "" else pat.object
                ok = ok and any((s == "*" or r[0] == s) and (o == "*" or r[2] == o) and self.is_sub(r[1], pat.predicate)
                                for r in self.relations if eid in (r[0], r[2]))
            if ok:
                out.append(Element(e.type, e.label, eid))
        return out

    def commit(self, ops):
        rows = []
        for o in ops:
            rel = (o.relation.subject, o.relation.predicate, o.relation.object)
            if o.kind == wm_op_t.ADD_RELATION:
                self.relations.add(rel)
            elif o.kind == wm_op_t.REMOVE_RELATION:
                if rel not in self.relations:
                    raise WorldModelError(f"no relation {rel} to remove")
                self.relations.discard(rel)
            rows.append((o.kind, rel))
        self.commits.append(rows)
        self.version += 1

    def load_scene_without(self, rel):
        """Another client replaced the world (skillbus wm load): the reset change."""
        self.relations.discard(rel)
        self.version += 1
        ch = wm_change_t()
        ch.version, ch.reset = self.version, True
        return ch.encode()


@pytest.fixture
def server():
    return Server()


@pytest.fixture
def wmi(monkeypatch, server):
    def resync(self):
        self._elements = {k: e.clone() for k, e in server.elements.items()}
        self._relations, self._by_node = set(), {}
        for r in server.relations:
            self._add_rel(r)
        self._subproperty_cache.clear()
        self.version, self._stale = server.version, False

    monkeypatch.setattr(WorldModelInterface, "resync", resync)
    w = WorldModelInterface(open_bus("memq://"), "test", timeout=0.2)
    w.query = server.query
    w.commit = lambda ops, expected_version=-1: server.commit(ops)
    w._server_version = lambda: server.version
    return w


# -- the ontology, as far as the world uses it ------------------------------------------------
def test_sub_properties_are_those_the_world_uses_below_the_parent(wmi):
    assert wmi.get_sub_properties("skiros:spatiallyRelated") == ["skiros:spatiallyRelated", "skiros:at",
                                                                 "skiros:contain"]
    assert wmi.get_sub_properties("skiros:contain") == ["skiros:contain"]
    assert wmi.is_subproperty("skiros:contain", "skiros:spatiallyRelated")
    assert not wmi.is_subproperty("skiros:hasTemplate", "skiros:spatiallyRelated")
    with pytest.raises(NotImplementedError, match="direct subproperties"):
        wmi.get_sub_properties("skiros:spatiallyRelated", recursive=False)


def test_sub_classes_individuals_and_types(wmi):
    assert wmi.get_sub_classes("skiros:Location") == ["skiros:Location", "skiros:Bin", "skiros:Table"]
    assert wmi.get_sub_classes("skiros:Product") == ["skiros:Product", "skiros:Cube"]
    assert wmi.get_sub_classes("skiros:Unicorn") == []
    assert wmi.get_individuals("skiros:Location") == ["skiros:Bin-5", "skiros:Table-1"]
    assert wmi.get_individuals("skiros:Location", recursive=False) == []
    assert wmi.get_types("skiros:Cube") == ["skiros:Cube-2", "skiros:Cube-3"]
    assert wmi.get_type("skiros:Cube-2") == ["skiros:Cube"] and wmi.get_type("skiros:Cube-9") == []


def test_what_the_server_cannot_answer_says_why(wmi):
    for call, why in ((lambda: wmi.get_super_class("skiros:Cube"), "lists its ontology"),
                      (lambda: wmi.add_class("skiros:Mug", "skiros:Product"), "cannot add ontology classes"),
                      (lambda: wmi.get_template_element("skiros:test_robot"), "keeps no individuals"),
                      (lambda: wmi.instanciate("skiros:test_robot"), "keeps no individuals"),
                      (lambda: wmi.lock(), "expected_version"), (lambda: wmi.unlock(), "no lock"),
                      (lambda: wmi.get_sub_classes("skiros:Location", False), "direct subclasses")):
        with pytest.raises(NotImplementedError, match=why):
            call()
    assert wmi.get_reasoner("skiros:contain") is None and wmi.get_reasoner_relations(None, ":pX", None) is None


# -- the world --------------------------------------------------------------------------------
def test_triples_rows_hold_the_terms_not_given(wmi):
    assert wmi.get_triples("skiros:Table-1", "skiros:contain") == ["skiros:Cube-2", "skiros:Cube-3"]
    assert wmi.get_triples(None, "skiros:at") == ["skiros:Gripper-7 skiros:Table-1 "]
    assert wmi.get_triples("skiros:Cube-2", "rdf:type") == ["skiros:Cube"]
    assert wmi.get_triples("skiros:Cube-2", "skiros:Weight") == ["0.2"]
    assert "skiros:Table-1 table " in wmi.get_triples(pred="rdfs:label")


def test_branch_follows_scene_relations_depth_first(wmi, server):
    server.relations.add(("skiros:Cube-2", "skiros:contain", "skiros:Table-1"))  # a loop is followed once
    wmi.resync()
    ids = [e.id for e in wmi.get_branch("skiros:Table-1")]
    # (skiros:hasTemplate is no scene relation; skillbus's ontology has no skiros:sceneProperty)
    assert ids == ["skiros:Table-1", "skiros:Cube-2", "skiros:Cube-3"]
    assert [e.id for e in wmi.get_branch("skiros:Gripper-7", "skiros:spatiallyRelated")] == [
        "skiros:Gripper-7", "skiros:Table-1", "skiros:Cube-2", "skiros:Cube-3"]
    assert [e.id for e in wmi.get_branch("skiros:Gripper-7", "skiros:at")] == ["skiros:Gripper-7", "skiros:Table-1"]
    assert [e.id for e in wmi.get_branch("skiros:Gripper-7", "", "skiros:Bin")] == ["skiros:Gripper-7"]
    with pytest.raises(WorldModelError):
        wmi.get_branch("skiros:Cube-9")


def test_check_relation(wmi):
    table, cube, bin_ = (wmi.get_element(i) for i in ("skiros:Table-1", "skiros:Cube-2", "skiros:Bin-5"))
    assert wmi.check_relation(table, "skiros:contain", cube, True, False)
    assert wmi.check_relation(table, "skiros:spatiallyRelated", cube, True, False)  # a subproperty counts
    assert wmi.check_relation(bin_, "skiros:contain", cube, False, False)
    assert wmi.check_relation(table, "skiros:hasTemplate", bin_, True, True)
    templ = Element("skiros:Table")
    templ.setProperty("skiros:Template", "skiros:Table-1")
    assert wmi.check_relation(templ, "skiros:contain", cube, True, True)


def test_instanciate_adds_an_element_template_with_the_given_relations(wmi):
    added = []
    wmi.add_element = lambda e: added.append(e) or e
    t = Element("skiros:Cube", "blue", "skiros:Cube-2")
    t.addRelation("skiros:Table-1", "skiros:contain", "-1")
    e = wmi.instanciate(t, relations=[{"src": "skiros:Bin-5", "type": "skiros:contain", "dst": "-1", "state": True,
                                       "abstract": False}])
    assert added == [e] and e.id == "" and e.label == "blue" and t.id == "skiros:Cube-2"
    assert [(r["src"], r["dst"]) for r in e.getRelations()] == [("skiros:Bin-5", "-1")]
    t.addRelation("-1", "skiros:hasA", "skiros:Gripper-7")
    with pytest.raises(NotImplementedError, match="recursive"):
        wmi.instanciate(t, recursive=True)


# -- set_relation decides on the server's world, not on a replica that lags ------------------------
TABLE_CUBE = ("skiros:Table-1", "skiros:contain", "skiros:Cube-2")


def test_set_relation_after_a_scene_load_the_replica_heard_of(wmi, server):
    wmi._on_change(server.load_scene_without(TABLE_CUBE))  # the replica saw the reset...
    assert TABLE_CUBE in wmi._relations  # ...but has not read the new world yet
    assert wmi.set_relation(*TABLE_CUBE, True)
    assert server.commits == [[(wm_op_t.ADD_RELATION, TABLE_CUBE)]]


def test_set_relation_after_a_scene_load_the_replica_did_not_hear_of_yet(wmi, server):
    server.load_scene_without(TABLE_CUBE)  # its reset change is still on its way (or lost)
    assert wmi.set_relation(*TABLE_CUBE, True)
    assert server.commits == [[(wm_op_t.ADD_RELATION, TABLE_CUBE)]] and TABLE_CUBE in server.relations


def test_set_relation_writes_nothing_when_the_world_is_already_so(wmi, server):
    assert wmi.set_relation(*TABLE_CUBE, True)
    assert wmi.set_relation("skiros:Bin-5", "skiros:contain", "skiros:Cube-2", False)
    assert server.commits == []
    assert wmi.set_relation(*TABLE_CUBE, False)
    assert server.commits == [[(wm_op_t.REMOVE_RELATION, TABLE_CUBE)]]
