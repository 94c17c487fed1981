"""SPARQL on the world model (SkiROS2's query_ontology), answered by the server through
Rasqal: over the ontology (subclass paths), the loaded scene's elements and their
relations, in SkiROS2's answer form; a CONSTRUCT's triples as rows; a query that may read
other files or hosts (FROM, SERVICE), a DESCRIBE and a malformed one are refused naming
why; so are queries whose results or work have no bound (patterns joined by no
variable); the server goes on, and a query after a change of the world sees the change (the
server keeps the world's graph between queries of one version)."""

import json
import sys

from skillbus import paths

QUERY = """
from skillbus.bus import open_bus
from skillbus.world import WorldModelInterface
from skillbus.world.element import Element
import json, sys
wmi = WorldModelInterface(open_bus())
out = {}
for name, q in json.loads(sys.argv[1]).items():
    try:
        out[name] = wmi.query_ontology(q)
    except Exception as e:
        out[name] = "error: " + str(e)
spare = wmi.add_element(Element("skiros:Cube", "spare"))
out["after_adding"] = wmi.query_ontology(json.loads(sys.argv[1])["labels"])
out["spare"] = spare.id
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
    # an OPTIONAL that binds nothing: the value is left out (the client raised TypeError on
    # the "type": "unbound" value Rasqal's writer gave)
    "optional": "SELECT ?x ?w WHERE { ?x a skiros:Cube OPTIONAL { ?x skiros:NoSuchProperty ?w } } ORDER BY ?x",
    # DISTINCT, with OFFSET and LIMIT after it (applied by the server, not by Rasqal)
    "distinct": "SELECT DISTINCT ?c WHERE { ?t a skiros:Table ; skiros:contain ?x . ?x a ?c } ORDER BY ?c LIMIT 5",
    "ask": "ASK { skiros:Bin-5 a skiros:Bin }",
    "construct": "CONSTRUCT { ?x skiros:near ?t } WHERE { ?t a skiros:Table . ?t skiros:contain ?x . "
                 "?x a skiros:Cube }",
    "describe": "DESCRIBE skiros:Bin-5",
    "from": "SELECT ?x FROM <file:///etc/passwd> WHERE { ?x ?p ?o }",
    "service": "SELECT ?x WHERE { SERVICE <http://example.org/sparql> { ?x ?p ?o } }",
    "broken": "SELECT ?x WHERE { ?x a }",
    # patterns that share no variable: rows by the graph's size cubed. The results took
    # the server's memory (2 GB in 10 s) and it answered nothing more; now they stop at
    # the reply's size, the work at its bound, a sort at its lower one.
    "cross": "SELECT * WHERE { ?a ?b ?c . ?d ?e ?f . ?g ?h ?i }",
    "cross_count": "SELECT (COUNT(*) AS ?n) WHERE { ?a ?b ?c . ?d ?e ?f . ?g ?h ?i . ?j ?k ?l }",
    "cross_sorted": "SELECT ?a WHERE { ?a ?b ?c . ?d ?e ?f } ORDER BY ?a",
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
    assert r["optional"] == ["skiros:Cube-2 ", "skiros:Cube-3 ", "skiros:Cube-4 "], r
    assert r["distinct"] == ["skiros:Cube", "owl:NamedIndividual"], r  # (ORDER BY: by IRI)
    assert r["ask"] == ["true"], r
    assert sorted(r["construct"]) == [f"skiros:Cube-{i} skiros:near skiros:Table-1 " for i in (2, 3, 4)], r
    assert r["describe"].startswith("error:") and "DESCRIBE is not answered" in r["describe"], r
    assert r["after_adding"] == sorted(r["labels"] + [f"{r['spare']} spare "], key=lambda row: row.split(" ", 1)[1]), r
    assert r["from"].startswith("error:") and "FROM" in r["from"], r
    assert r["service"].startswith("error:") and "SERVICE" in r["service"], r
    assert r["broken"].startswith("error: SPARQL"), r
    assert "more than a reply carries: add LIMIT and OFFSET" in r["cross"], r
    assert "looked at more than 2000000 triples" in r["cross_count"], r
    assert "looked at more than 5000 triples" in r["cross_sorted"] and "sort on the client" in r["cross_sorted"], r
    assert wm.returncode is None
