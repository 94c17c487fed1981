"""SPARQL on the world model (SkiROS2's query_ontology), answered by the server through
Rasqal: over the ontology (subclass paths), the loaded scene's elements and their
relations, in SkiROS2's answer form; a query that may read other files or hosts (FROM,
SERVICE) and a malformed one are refused naming why; the server goes on."""

import json
import sys

from skillbus import paths

QUERY = """
from skillbus.bus import open_bus
from skillbus.world import WorldModelInterface
import json, sys
wmi = WorldModelInterface(open_bus())
out = {}
for name, q in json.loads(sys.argv[1]).items():
    try:
        out[name] = wmi.query_ontology(q)
    except Exception as e:
        out[name] = "error: " + str(e)
print(json.dumps(out))
"""

QUERIES = {
    # the ontology: the direct subclasses of Product (Rasqal has no property paths: no
    # rdfs:subClassOf*)
    "products": "SELECT ?c WHERE { ?c rdfs:subClassOf skiros:Product } ORDER BY ?c",
    # the world: what the table holds, whose class is a Product's subclass
    "on_table": "SELECT ?x WHERE { ?t a skiros:Table . ?t skiros:contain ?x . ?x a ?c . "
                "?c rdfs:subClassOf skiros:Product } ORDER BY ?x",
    "labels": "SELECT ?x ?l WHERE { ?x a skiros:Cube ; rdfs:label ?l } ORDER BY ?l",
    "ask": "ASK { skiros:Bin-5 a skiros:Bin }",
    "from": "SELECT ?x FROM <file:///etc/passwd> WHERE { ?x ?p ?o }",
    "service": "SELECT ?x WHERE { SERVICE <http://example.org/sparql> { ?x ?p ?o } }",
    "broken": "SELECT ?x WHERE { ?x a }",
}


def test_sparql_on_the_world_model(sandbox, tmp_path):
    wm = sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", str(tmp_path / "wm"),
                              "--scene", str(paths.demo_scene().with_suffix("").with_suffix(".ttl"))])
    wm.wait_for("serving", 30)
    p = sandbox.start("query", [sys.executable, "-c", QUERY, json.dumps(QUERIES)])
    assert sandbox.wait(p, 60) == 0, p.stderr()
    r = json.loads(p.stdout().strip().splitlines()[-1])
    assert "skiros:Cube" in r["products"] and "skiros:Table" not in r["products"], r
    assert r["on_table"] == ["skiros:Cube-2", "skiros:Cube-3", "skiros:Cube-4"], r
    assert r["labels"] == ["skiros:Cube-4 blue ", "skiros:Cube-3 green ", "skiros:Cube-2 red "], r
    assert r["ask"] == ["true"], r
    assert r["from"].startswith("error:") and "FROM" in r["from"], r
    assert r["service"].startswith("error:") and "SERVICE" in r["service"], r
    assert r["broken"].startswith("error: SPARQL"), r
    assert wm.returncode is None
