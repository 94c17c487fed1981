"""SkiROS2's ontology questions and changes on a live world model server: a scene that
imports an ontology from the server's --ontology-library is loaded with it (and keeps it
across a restart after the library file is gone); get_super_class, direct and recursive
get_sub_classes / get_sub_properties from the server's hierarchy; templates (ontology
individuals) as Elements and instanciated recursively; add_class while the server runs
(another client hears of it; a save carries the class, a restart keeps it; the skill
manager's side: test_ontology_sharing.py); the advisory lock between two clients; a SPARQL property path refused
naming why."""

from __future__ import annotations

import json
import signal
import sys
import textwrap

from skillbus import paths

ROBOT_OWL = """\
@prefix owl: <http://www.w3.org/2002/07/owl#> .
@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .
@prefix xsd: <http://www.w3.org/2001/XMLSchema#> .
@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .
@prefix kit: <http://example.org/kitchen.owl#> .

<http://example.org/kitchen.owl> a owl:Ontology .
kit:Cup a owl:Class ; rdfs:subClassOf skiros:Product .
kit:Mug a owl:Class ; rdfs:subClassOf kit:Cup .
kit:Handle a owl:Class ; rdfs:subClassOf skiros:Product .
kit:mug_template a owl:NamedIndividual, kit:Mug ;
    rdfs:label "mug" ;
    skiros:Weight "0.3"^^xsd:double ;
    skiros:hasA kit:handle_template .
kit:handle_template a owl:NamedIndividual, kit:Handle ;
    skiros:hasA kit:mug_template .
"""

SCENE = """\
@prefix owl: <http://www.w3.org/2002/07/owl#> .
@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .
@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .
@prefix kit: <http://example.org/kitchen.owl#> .

<http://example.org/scenes/kitchen> a owl:Ontology ; owl:imports <http://example.org/kitchen.owl> .
skiros:Table-1 a owl:NamedIndividual, skiros:Table ; rdfs:label "table" ; skiros:contain kit:Mug-2 .
kit:Mug-2 a owl:NamedIndividual, kit:Mug ; rdfs:label "red mug" .
"""

CLIENT = textwrap.dedent("""
    import json, sys
    from skillbus.bus import open_bus
    from skillbus.world import WorldModelInterface
    wmi = WorldModelInterface(open_bus(), "api-test")
    other = WorldModelInterface(open_bus(), "api-test-2")
    out = {}
    def ask(name, f):
        try:
            out[name] = f()
        except Exception as e:
            out[name] = f"error {type(e).__name__}: {e}"
    ask("report", lambda: wmi.load_scene(turtle=sys.argv[1]))
    ask("sub_recursive", lambda: wmi.get_sub_classes("skiros:Product"))
    ask("sub_direct", lambda: wmi.get_sub_classes("kit:Cup", recursive=False))
    ask("super", lambda: wmi.get_super_class("kit:Mug"))
    ask("super_unknown", lambda: wmi.get_super_class("kit:Unicorn"))
    ask("props_direct", lambda: wmi.get_sub_properties("skiros:spatiallyRelated", recursive=False))
    ask("props_recursive", lambda: wmi.get_sub_properties("skiros:spatiallyRelated"))
    ask("individuals", lambda: wmi.get_individuals("kit:Cup"))
    ask("individuals_exact", lambda: wmi.get_individuals("kit:Cup", recursive=False))
    ask("type_of_template", lambda: wmi.get_type("kit:mug_template"))
    def template():
        e = wmi.get_template_element("kit:mug_template")
        return [e.type, e.label, e.getProperty("skiros:Weight").value, e.getProperty("skiros:Template").value,
                sorted((r["src"], r["type"], r["dst"]) for r in e.getRelations())]
    ask("template", template)
    ask("template_unknown", lambda: wmi.get_template_element("kit:nothing"))
    def instanciate():
        mug = wmi.instanciate("kit:mug_template", recursive=True, relations=[
            {"src": "skiros:Table-1", "type": "skiros:contain", "dst": "-1", "state": True, "abstract": False}])
        handles = wmi.get_relations(mug.id, "skiros:hasA", "")
        return [mug.type, mug.label, wmi.get_element(mug.id).getProperty("skiros:Weight").value,
                wmi.has_relation("skiros:Table-1", "skiros:contain", mug.id),
                [wmi.get_element(r["dst"]).type for r in handles]]
    ask("instanciate", instanciate)
    ask("add_class_unknown_parent", lambda: wmi.add_class("kit:Teapot", "kit:Kettle"))
    ask("add_class", lambda: wmi.add_class("kit:Teapot", "kit:Cup"))
    ask("teapot_super", lambda: wmi.get_super_class("kit:Teapot"))
    ask("other_sees_teapot", lambda: (other.sync(), other.get_sub_classes("kit:Cup", recursive=False))[1])
    def add_teapot():
        from skillbus.world import Element
        return wmi.add_element(Element("kit:Teapot", "teapot")).id
    ask("teapot", add_teapot)
    ask("lock", lambda: wmi.lock())
    ask("lock_again", lambda: wmi.lock())
    ask("other_lock", lambda: other.lock(timeout=0.3))
    ask("other_unlock", lambda: other.unlock())
    ask("other_lock_after", lambda: other.lock(timeout=0.3))
    ask("unlock", lambda: other.unlock())
    ask("unlock_free", lambda: wmi.unlock())
    def anonymous_lock():
        from skillbus.msgs import wm_lock_t
        req = wm_lock_t()
        req.lock = True
        return wmi._call("lock", req, wm_lock_t).ok
    ask("lock_without_holder", anonymous_lock)
    ask("path", lambda: wmi.query_ontology("SELECT ?x WHERE { ?x rdfs:subClassOf* skiros:Product }"))
    def axioms(turtle):
        from skillbus.msgs import wm_scene_t
        req = wm_scene_t()
        req.turtle = turtle
        return wmi._call("add_axioms", req, wm_scene_t).report
    ask("axiom_on_element", lambda: axioms('skiros:Table-1 rdfs:comment "x" .'))
    ask("axiom_blank", lambda: axioms('kit:Cup rdfs:subClassOf [ a owl:Restriction ] .'))
    ask("axiom_broken", lambda: axioms('kit:Cup rdfs:subClassOf .'))
    ask("axiom_again", lambda: axioms('kit:Teapot rdfs:subClassOf kit:Cup .'))
    # a typed literal whose text is no integer: written as Turtle for the journal's scene
    # files, it must read back as it is (not as an integer and a triple more)
    ask("axiom_literal", lambda: axioms('kit:Cup rdfs:comment "7 . kit:Spoon rdfs:subClassOf kit:Cup"^^xsd:integer .'))
    ask("saved", lambda: wmi.save_scene())
    print(json.dumps(out))
""")

AFTER_RESTART = textwrap.dedent("""
    import json
    from skillbus.bus import open_bus
    from skillbus.world import WorldModelInterface
    wmi = WorldModelInterface(open_bus(), "api-test-3")
    print(json.dumps({"sub": wmi.get_sub_classes("kit:Cup"), "template": wmi.get_type("kit:mug_template"),
                      "mugs": wmi.get_individuals("kit:Mug"),
                      "comment": wmi.query_ontology("SELECT ?c WHERE { kit:Cup rdfs:comment ?c }")}))
""")


def run(sandbox, code, *args):
    p = sandbox.start(f"client-{len(sandbox.procs)}", [sys.executable, "-c", code, *args])
    assert sandbox.wait(p, 90) == 0, p.stderr()
    return json.loads(p.stdout().strip().splitlines()[-1])


def test_ontology_questions_templates_classes_and_the_lock(sandbox, tmp_path):
    library = tmp_path / "library"
    library.mkdir()
    (library / "kitchen.ttl").write_text(ROBOT_OWL)
    data = tmp_path / "wm"
    wm_cmd = [paths.binary("wm_server"), "--wall-clock", "--data", str(data), "--ontology-library", str(library)]
    wm = sandbox.start("wm", wm_cmd)
    wm.wait_for("serving", 30)

    r = run(sandbox, CLIENT, SCENE)
    assert "imported the ontology" in r["report"] and "kitchen.ttl" in r["report"], r["report"]
    assert r["sub_recursive"][0] == "skiros:Product" and {"kit:Cup", "kit:Mug", "kit:Handle"} <= set(
        r["sub_recursive"]), r
    assert r["sub_direct"] == ["kit:Mug"], r
    assert r["super"] == "kit:Cup", r
    assert r["super_unknown"].startswith("error IndexError") and "no class" in r["super_unknown"], r
    assert "skiros:contain" in r["props_direct"] and "skiros:spatiallyRelated" not in r["props_direct"], r
    assert r["props_recursive"][0] == "skiros:spatiallyRelated" and "skiros:contain" in r["props_recursive"], r
    assert r["individuals"] == ["kit:Mug-2", "kit:mug_template"], r
    assert r["individuals_exact"] == [], r
    assert sorted(r["type_of_template"]) == ["kit:Mug", "owl:NamedIndividual"], r
    assert r["template"] == ["kit:Mug", "kit:mug_template", 0.3, "kit:mug_template",
                             [["-1", "skiros:hasA", "kit:handle_template"],
                              ["kit:handle_template", "skiros:hasA", "-1"]]], r
    assert r["template_unknown"].startswith("error WorldModelError") and "no individual" in r["template_unknown"]
    # recursive: the mug, on the table, with a handle; the handle's hasA back to the mug
    # template ends the loop
    assert r["instanciate"] == ["kit:Mug", "kit:mug_template", 0.3, True, ["kit:Handle"]], r
    assert "kit:Kettle is no class" in r["add_class_unknown_parent"], r
    assert r["add_class"] is True and r["teapot_super"] == "kit:Cup", r
    assert r["other_sees_teapot"] == ["kit:Mug", "kit:Teapot"], r
    assert r["teapot"].startswith("kit:Teapot-"), r
    assert r["lock"] is True and r["lock_again"] is True, r
    assert r["other_lock"].startswith("error TimeoutError") and "locked by" in r["other_lock"], r
    assert r["other_unlock"] is True and r["other_lock_after"] is True, r
    assert r["unlock"] is True and r["unlock_free"] is False, r
    assert "name the holder" in r["lock_without_holder"], r
    assert "property paths" in r["path"] and "get_sub_classes" in r["path"], r
    assert "is an element of the world" in r["axiom_on_element"], r
    assert "blank node" in r["axiom_blank"] and "line" in r["axiom_broken"], r
    assert r["axiom_again"] == "0 new statement(s)", r
    assert r["axiom_literal"] == "1 new statement(s)", r
    assert "kit:Teapot" in r["saved"] and "owl:imports" in r["saved"], r["saved"]
    assert wm.returncode is None

    # a restart without the library file: the scene's imported ontology and the added
    # class are the world model's own now
    sandbox.kill(wm, signal.SIGTERM)
    assert sandbox.wait(wm, 30) is not None
    (library / "kitchen.ttl").unlink()
    wm2 = sandbox.start("wm2", wm_cmd)
    wm2.wait_for("serving", 30)
    r2 = run(sandbox, AFTER_RESTART)
    assert r2["sub"] == ["kit:Cup", "kit:Mug", "kit:Teapot"], r2  # (no kit:Spoon)
    assert r2["comment"] == ["7 . kit:Spoon rdfs:subClassOf kit:Cup"], r2
    assert "kit:Mug" in r2["template"], r2
    assert r2["mugs"][0] == "kit:Mug-2" and "kit:mug_template" in r2["mugs"], r2


RELOAD = textwrap.dedent("""
    import json, sys
    from skillbus.bus import open_bus
    from skillbus.world import WorldModelInterface
    wmi = WorldModelInterface(open_bus(), "reload-test")
    out = {"first": wmi.load_scene(turtle=sys.argv[1]), "again": wmi.load_scene(turtle=sys.argv[1])}
    out["template"] = wmi.get_template_element("kit:mug_template").type
    out["mug_up"] = wmi.get_super_class("kit:Mug")
    from skillbus.msgs import wm_scene_t
    onto = wmi._call("ontology", wm_scene_t(), wm_scene_t).turtle
    out["ontology_has_mug"] = "kit:Mug" in onto or "kitchen.owl#Mug" in onto
    out["plain"] = wmi.load_scene(turtle=sys.argv[2])
    out["cup_after_plain"] = wmi.get_sub_classes("kit:Cup")
    print(json.dumps(out))
""")

PLAIN = """\
@prefix owl: <http://www.w3.org/2002/07/owl#> .
@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .
@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .
skiros:Table-1 a owl:NamedIndividual, skiros:Table ; rdfs:label "table" .
"""


def test_a_scene_loaded_again_imports_again_and_the_next_scene_replaces_its_ontology(sandbox, tmp_path):
    library = tmp_path / "library"
    library.mkdir()
    (library / "kitchen.ttl").write_text(ROBOT_OWL)
    wm = sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", str(tmp_path / "wm"),
                              "--ontology-library", str(library)])
    wm.wait_for("serving", 30)
    r = run(sandbox, RELOAD, SCENE, PLAIN)
    assert "imported the ontology" in r["first"] and "imported the ontology" in r["again"], r
    assert r["template"] == "kit:Mug" and r["mug_up"] == "kit:Cup" and r["ontology_has_mug"], r
    assert r["cup_after_plain"] == [], r  # the kitchen came with the scene, and went with it
