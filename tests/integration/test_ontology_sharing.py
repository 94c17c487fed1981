"""One ontology for the whole system: the skill manager, given no ontology files, judges by
the world model server's (its --ontology files, in RDF/XML or Turtle, and the loaded
scene's own axioms), read with the world, and a class a client adds while the server runs
(SkiROS2's add_class). Real wm_server, skill_mgr and skill process."""

import sys

from skillbus import paths
from test_skills import cli, start_system, start_wm

KITCHEN_OWL = """<?xml version="1.0"?>
<rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#"
         xmlns:rdfs="http://www.w3.org/2000/01/rdf-schema#"
         xmlns:owl="http://www.w3.org/2002/07/owl#">
  <owl:Class rdf:about="http://rvmi.aau.dk/ontologies/skiros.owl#Bread">
    <rdfs:subClassOf rdf:resource="http://rvmi.aau.dk/ontologies/skiros.owl#Product"/>
  </owl:Class>
</rdf:RDF>
"""

# The demo world plus a bread (a class from kitchen.owl) and a soda, whose class the
# scene itself declares.
EXTRA = """
skiros:Soda rdfs:subClassOf skiros:Product .
skiros:Bread-20 a skiros:Bread , owl:NamedIndividual ; rdfs:label "bread" .
skiros:Soda-21 a skiros:Soda , owl:NamedIndividual ; rdfs:label "soda" .
"""


def test_the_manager_judges_by_the_world_models_ontology(sandbox, tmp_path):
    owl = tmp_path / "kitchen.owl"
    owl.write_text(KITCHEN_OWL)
    scene = tmp_path / "kitchen.ttl"
    scene.write_text(paths.demo_scene().with_suffix("").with_suffix(".ttl").read_text() + EXTRA)
    default = paths.REPO_ROOT / "wm_server" / "ontology" / "skiros.ttl"
    wm = start_wm(sandbox, tmp_path / "wm", "--ontology", f"{default},{owl}", scene=scene)
    wm.wait_for("serving", 30)
    start_system(sandbox, "condition_skills", timeout=60)  # (the manager without --ontology)
    for subject in ("skiros:Bread-20", "skiros:Soda-21"):  # Product by the file, by the scene
        rc, out, err = cli(sandbox, "run", "CheckOnType", "-p", f"Subject={subject}", "--timeout", "30")
        assert rc == 0 and "Success" in out, out + err
    rc, out, err = cli(sandbox, "run", "CheckOnType", "-p", "Subject=skiros:Table-1", "--timeout", "30")
    assert rc == 1 and "IsProduct" in out, out + err  # and still not everything is one

    # a class added while everything runs: the manager reads the ontology again with the world
    add = sandbox.start("add", [sys.executable, "-c", ADD_MUFFIN])
    assert sandbox.wait(add, 60) == 0, add.stderr()
    muffin = add.stdout().strip().splitlines()[-1]
    assert muffin.startswith("skiros:Muffin-"), add.stdout()
    rc, out, err = cli(sandbox, "run", "CheckOnType", "-p", f"Subject={muffin}", "--timeout", "30")
    assert rc == 0 and "Success" in out, out + err


ADD_MUFFIN = """
from skillbus.bus import open_bus
from skillbus.world import Element, WorldModelInterface
wmi = WorldModelInterface(open_bus(), "add-muffin")
assert wmi.add_class("skiros:Muffin", "skiros:Bread")
print(wmi.add_element(Element("skiros:Muffin", "muffin")).id)
"""
