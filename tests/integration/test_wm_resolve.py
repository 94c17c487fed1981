"""resolve_elements is answered from the client's replica: here each of its answers is
compared with the server's own query (wm.query, the rules of wm_server's store) on a live
world, for types with subclasses, labels, property values of each type, and relation
patterns ("-1", "*", subproperties). The elements it returns are the reader's own: a
change to one is not seen by the replica, and update_element writes just that change.
The relations of an element stay in order as they change (the replica's sorted cache)."""

from __future__ import annotations

import json
import sys
import textwrap

from skillbus import paths

EXTRA = """
skiros:Cube-2 skiros:Price "0.25"^^xsd:double ; skiros:Count "3"^^xsd:int ; skiros:Fragile "true"^^xsd:boolean ;
    skiros:Tag "red", "small" .
skiros:Cube-3 skiros:Price "0.5"^^xsd:double ; skiros:Count "3"^^xsd:int ; skiros:Tag "small" .
"""

CLIENT = textwrap.dedent("""
    import json, sys
    from skillbus.bus import open_bus
    from skillbus.msgs import wm_query_t
    from skillbus.world import Element, WorldModelInterface
    from skillbus.world.client import WorldModelError, query_all
    from skillbus.world.convert import property_msg, relation_msg
    wmi = WorldModelInterface(open_bus(), "resolve-test")
    wmi.load_scene(turtle=sys.argv[1])

    def server(e):
        # the server's answer to the same question (as resolve_elements asked before)
        q = wm_query_t()
        q.type = e.type if e.type not in ("", "Unknown") else ""
        q.label = e.label
        q.properties = [property_msg(p) for p in e.properties if p.values]
        q.num_properties = len(q.properties)
        q.relations = [relation_msg("" if r["src"] == "-1" else r["src"], r["type"],
                                    "" if r["dst"] == "-1" else r["dst"]) for r in e.getRelations()]
        q.num_relations = len(q.relations)
        q.ids_only = True
        return [m.id for m in query_all(lambda req, t: wmi._call_elements("query", req, t), q, timeout=5)]

    def case(etype="", label="", props=(), rels=()):
        e = Element(etype, label)
        for k, v in props:
            e.setProperty(k, v)
        for r in rels:
            e.addRelation(*r)
        try:
            ours = [x.id for x in wmi.resolve_elements(e)]
        except WorldModelError as err:
            ours = "error: " + str(err)
        try:
            theirs = server(e)
        except WorldModelError as err:
            theirs = "error: " + str(err)
        return [ours, theirs]

    out = {
        "products": case("skiros:Product"),
        "locations": case("skiros:Location"),
        "exact": case("skiros:Cube"),
        "unknown": case("skiros:Unicorn"),
        "label": case("", "red"),
        "type_and_label": case("skiros:Product", "green"),
        "float": case("skiros:Product", props=[("skiros:Price", 0.25)]),
        "int": case("", props=[("skiros:Count", 3)]),
        "int_is_not_float": case("", props=[("skiros:Count", 3.0)]),
        "bool": case("", props=[("skiros:Fragile", True)]),
        "two_values": case("", props=[("skiros:Tag", ["small", "red"])]),
        "one_of_two": case("", props=[("skiros:Tag", "small")]),
        "missing_value": case("", props=[("skiros:Tag", "blue")]),
        "contained_by_table": case("skiros:Product", rels=[("skiros:Table-1", "skiros:contain", "-1")]),
        "by_subproperty": case("", rels=[("skiros:Table-1", "skiros:spatiallyRelated", "-1")]),
        "contains_anything": case("", rels=[("-1", "skiros:contain", "*")]),
        "any_relation_to_table": case("", rels=[("*", "", "skiros:Table-1")]),
        "two_patterns": case("", rels=[("-1", "skiros:contain", "*"), ("*", "skiros:contain", "-1")]),
        "nothing": case("skiros:Product", rels=[("skiros:Bin-5", "skiros:contain", "-1")]),
    }
    # the reader's own copies
    cube = wmi.resolve_elements(Element("skiros:Product", "red"))[0]
    cube.setProperty("skiros:Price", 9.0)
    again = wmi.resolve_elements(Element("skiros:Product", "red"))[0]
    out["copy_independent"] = again.getProperty("skiros:Price").value
    out["changed"] = cube.changed_since_loaded()
    wmi.update_element(cube)
    out["after_update"] = [wmi.get_element(cube.id).getProperty("skiros:Price").value,
                           wmi.get_element(cube.id).getProperty("skiros:Tag").values]
    # relations stay sorted as they change
    table = wmi.get_element("skiros:Table-1")
    before = [(r["src"], r["type"], r["dst"]) for r in table.getRelations()]
    wmi.set_relation("skiros:Table-1", "skiros:contain", "skiros:Bin-5")
    after = [(r["src"], r["type"], r["dst"]) for r in wmi.get_element("skiros:Table-1").getRelations()]
    out["relations"] = [before == sorted(before), after == sorted(after),
                        ("skiros:Table-1", "skiros:contain", "skiros:Bin-5") in after, len(after) - len(before)]
    wmi.set_relation("skiros:Table-1", "skiros:contain", "skiros:Bin-5", False)
    out["removed"] = [(r["src"], r["type"], r["dst"]) for r in wmi.get_element("skiros:Table-1").getRelations()] == before
    print(json.dumps(out))
""")


def test_resolve_from_the_replica_answers_as_the_server(sandbox, tmp_path):
    scene = paths.demo_scene().with_suffix("").with_suffix(".ttl").read_text() + EXTRA
    wm = sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", str(tmp_path / "wm")])
    wm.wait_for("serving", 30)
    p = sandbox.start("client", [sys.executable, "-c", CLIENT, scene])
    assert sandbox.wait(p, 90) == 0, p.stderr()
    r = json.loads(p.stdout().strip().splitlines()[-1])
    for name in ("products", "locations", "exact", "unknown", "label", "type_and_label", "float", "int",
                 "int_is_not_float", "bool", "two_values", "one_of_two", "missing_value", "contained_by_table",
                 "by_subproperty", "contains_anything", "any_relation_to_table", "two_patterns", "nothing"):
        ours, theirs = r[name]
        if isinstance(theirs, str):  # an error: the same reason (the wording may differ)
            assert isinstance(ours, str) and theirs.split("failed: ")[-1] in ours, (name, ours, theirs)
        else:
            assert ours == theirs, (name, ours, theirs)
    # and the cases say something: each kind of answer occurs
    assert r["products"][0] == ["skiros:Cube-2", "skiros:Cube-3", "skiros:Cube-4"], r["products"]
    assert r["unknown"][0].startswith("error: unknown type 'skiros:Unicorn'"), r["unknown"]
    assert r["float"][0] == ["skiros:Cube-2"] and r["int"][0] == ["skiros:Cube-2", "skiros:Cube-3"], r
    assert r["int_is_not_float"][0] == [] and r["two_values"][0] == ["skiros:Cube-2"], r
    assert r["one_of_two"][0] == ["skiros:Cube-2", "skiros:Cube-3"] and r["missing_value"][0] == [], r
    assert r["by_subproperty"][0] == r["contained_by_table"][0] != [], r
    assert r["nothing"][0] == [], r
    assert r["copy_independent"] == 0.25 and r["changed"] is True, r
    assert r["after_update"] == [9.0, ["red", "small"]], r
    assert r["relations"] == [True, True, True, 1] and r["removed"] is True, r
