"""SkiROS2's ontology and world questions on the world-model client (get_sub_properties,
get_sub_classes, get_super_class, get_individuals, get_type(s), get_triples, get_branch,
check_relation, get_template_element, instanciate), and set_relation after the world was
replaced behind the replica's back. No server: the replica is filled by hand, the
server's answers (its hierarchy, query, commit, its version, a resync) are played here;
tests/integration/test_skiros2_ontology_api.py asks a live server."""

from __future__ import annotations

import pytest

from skillbus.bus import open_bus
from skillbus.msgs import wm_change_t, wm_op_t
from skillbus.world import Element
from skillbus.world.client import WorldModelError, WorldModelInterface
from skillbus.world.ontology_view import OntologyView

SUBPROPERTIES = {("skiros:contain", "skiros:spatiallyRelated"), ("skiros:at", "skiros:spatiallyRelated")}
SUBCLASSES = {("skiros:Cube", "skiros:Product"), ("skiros:Cube", "skiros:PhysicalObject"),
              ("skiros:Table", "skiros:Location"), ("skiros:Bin", "skiros:Location"),
              ("skiros:Table", "skiros:PhysicalObject"), ("skiros:Bin", "skiros:PhysicalObject"),
              ("skiros:Product", "skiros:PhysicalObject"), ("skiros:Location", "skiros:PhysicalObject"),
              ("skiros:Gripper", "skiros:PhysicalObject")}
CONCEPTS = {c for pair in SUBCLASSES for c in pair}
# Only direct superclasses go in the hierarchy (the server's answer)
DIRECT = {("skiros:Cube", "skiros:Product"), ("skiros:Table", "skiros:Location"), ("skiros:Bin", "skiros:Location"),
          ("skiros:Product", "skiros:PhysicalObject"), ("skiros:Location", "skiros:PhysicalObject"),
          ("skiros:Gripper", "skiros:PhysicalObject")}
TEMPLATES = {
    "skiros:bin_template": [["rdf:type", "owl:NamedIndividual", "", ""], ["rdf:type", "skiros:Bin", "", ""],
                            ["skiros:Weight", "1.5", "xsd:double", ""], ["skiros:hasA", "skiros:lid_template", "", ""]],
    "skiros:lid_template": [["rdf:type", "skiros:Product", "", ""], ["skiros:partOf", "skiros:bin_template", "", ""]],
}


def hierarchy() -> OntologyView:
    classes = {c: [up for (x, up) in DIRECT if x == c] for c in CONCEPTS}
    relations = {"skiros:spatiallyRelated": [], "skiros:hasTemplate": [], "skiros:hasA": [], "skiros:partOf": [],
                 **{p: [up] for (p, up) in SUBPROPERTIES}}
    return OntologyView.from_json({"classes": classes, "relations": relations, "individuals": TEMPLATES})


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
        self._relations, self._by_node, self._rel_cache = set(), {}, {}
        for r in server.relations:
            self._add_rel(r)
        self._ontology_cache = hierarchy()
        self.version, self._stale = server.version, False

    monkeypatch.setattr(WorldModelInterface, "resync", resync)
    w = WorldModelInterface(open_bus("memq://"), "test", timeout=0.2)
    w.query = server.query
    w.commit = lambda ops, expected_version=-1: server.commit(ops)
    w._server_version = lambda: server.version
    return w


# -- the ontology ---------------------------------------------------------------------------------
def test_sub_properties_recursive_and_direct(wmi):
    assert wmi.get_sub_properties("skiros:spatiallyRelated") == ["skiros:spatiallyRelated", "skiros:at",
                                                                 "skiros:contain"]
    assert wmi.get_sub_properties("skiros:contain") == ["skiros:contain"]
    assert wmi.get_sub_properties("skiros:spatiallyRelated", recursive=False) == ["skiros:at", "skiros:contain"]
    assert wmi.get_sub_properties("skiros:nearby") == []
    assert wmi.is_subproperty("skiros:contain", "skiros:spatiallyRelated")
    assert not wmi.is_subproperty("skiros:hasTemplate", "skiros:spatiallyRelated")


def test_sub_classes_super_class_individuals_and_types(wmi):
    assert wmi.get_sub_classes("skiros:Location") == ["skiros:Location", "skiros:Bin", "skiros:Table"]
    assert wmi.get_sub_classes("skiros:PhysicalObject") == [
        "skiros:PhysicalObject", "skiros:Gripper", "skiros:Location", "skiros:Product", "skiros:Bin", "skiros:Cube",
        "skiros:Table"]  # level by level
    assert wmi.get_sub_classes("skiros:PhysicalObject", recursive=False) == [
        "skiros:Gripper", "skiros:Location", "skiros:Product"]
    assert wmi.get_sub_classes("skiros:Unicorn") == [] and wmi.get_sub_classes("skiros:Unicorn", False) == []
    assert wmi.get_super_class("skiros:Cube") == "skiros:Product"
    for cls, why in (("skiros:PhysicalObject", "has no superclass"), ("skiros:Unicorn", "no class")):
        with pytest.raises(IndexError, match=why):
            wmi.get_super_class(cls)
    # the world's elements and the ontology's individuals
    assert wmi.get_individuals("skiros:Location") == ["skiros:Bin-5", "skiros:Table-1", "skiros:bin_template"]
    assert wmi.get_individuals("skiros:Location", recursive=False) == []
    assert wmi.get_individuals("skiros:Unicorn") == []
    assert wmi.get_types("skiros:Cube") == ["skiros:Cube-2", "skiros:Cube-3"]
    assert wmi.get_types("skiros:Product") == ["skiros:lid_template"]
    assert wmi.get_type("skiros:Cube-2") == ["skiros:Cube"] and wmi.get_type("skiros:Cube-9") == []
    assert wmi.get_type("skiros:bin_template") == ["owl:NamedIndividual", "skiros:Bin"]
    assert wmi.is_instance_of("skiros:Cube-2", "skiros:PhysicalObject")
    assert not wmi.is_instance_of("skiros:Cube-2", "skiros:Location")
    assert not wmi.is_instance_of("skiros:Cube-9", "skiros:Cube")


def test_templates_are_elements_made_from_the_ontologys_individuals(wmi):
    e = wmi.get_template_element("skiros:bin_template")
    assert (e.id, e.type, e.label) == ("", "skiros:Bin", "skiros:bin_template")
    assert e.getProperty("skiros:Weight").value == 1.5
    assert e.getProperty("skiros:Template").value == "skiros:bin_template"
    assert sorted((r["src"], r["type"], r["dst"]) for r in e.getRelations()) == [
        ("-1", "skiros:hasA", "skiros:lid_template"), ("skiros:lid_template", "skiros:partOf", "-1")]
    with pytest.raises(WorldModelError, match="no individual"):
        wmi.get_template_element("skiros:Bin-5")  # an element of the world, not of the ontology
    assert wmi.get_reasoner("skiros:contain") is None and wmi.get_reasoner_relations(None, ":pX", None) is None


def test_add_class_refuses_an_unknown_parent_before_asking_the_server(wmi):
    wmi._call = lambda *a, **k: pytest.fail("asked the server")
    with pytest.raises(WorldModelError, match="skiros:Kettle is no class"):
        wmi.add_class("skiros:Teapot", "skiros:Kettle")
    assert wmi.add_class("skiros:Cube", "skiros:Product")  # already so: nothing to add
    with pytest.raises(ValueError, match="no prefixed name"):
        wmi.add_class("Teapot", "skiros:Product")


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

    def add_element(e):
        e._id = f"skiros:New-{len(added)}"
        added.append(e)
        return e

    wmi.add_element = add_element
    t = Element("skiros:Cube", "blue", "skiros:Cube-2")
    t.addRelation("skiros:Table-1", "skiros:contain", "-1")
    e = wmi.instanciate(t, relations=[{"src": "skiros:Bin-5", "type": "skiros:contain", "dst": "-1", "state": True,
                                       "abstract": False}])
    assert added == [e] and e.label == "blue" and t.id == "skiros:Cube-2"
    assert [(r["src"], r["dst"]) for r in e.getRelations()] == [("skiros:Bin-5", "-1")]
    # recursive: the bin's lid (hasA) is made and related to it; the lid's partOf back to the
    # bin template is no hasA or contain, and the bin template is made once anyway
    added.clear()
    b = wmi.instanciate("skiros:bin_template", recursive=True)
    assert [(x.type, x.label) for x in added] == [("skiros:Bin", "skiros:bin_template"),
                                                 ("skiros:Product", "skiros:lid_template")]
    lid = added[1]
    assert [(r["src"], r["type"], r["dst"]) for r in lid.getRelations()] == [("skiros:New-0", "skiros:hasA", "-1")]
    assert ("-1", "skiros:hasA", "skiros:New-1") in [(r["src"], r["type"], r["dst"]) for r in b.getRelations()]
    added.clear()
    wmi.instanciate("skiros:bin_template", recursive=True, relation_filter=[])  # any relation: partOf too
    assert len(added) == 2  # the lid's partOf names the bin template, already made in this call


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


def test_the_ontology_is_read_again_after_the_world_was_replaced(wmi, server):
    wmi._ontology_cache = OntologyView.from_json({"classes": {"skiros:Unicorn": []}, "relations": {}})
    assert wmi.get_sub_classes("skiros:Unicorn") == ["skiros:Unicorn"]  # (what it holds now)
    wmi._on_change(server.load_scene_without(TABLE_CUBE))  # a scene load (or add_class) elsewhere
    assert wmi.get_sub_classes("skiros:Unicorn") == []  # read again with the world
    assert wmi.get_sub_classes("skiros:Location") == ["skiros:Location", "skiros:Bin", "skiros:Table"]
