"""Replies of any size arrive whole, between real processes: the world model server (C++)
sends a reply larger than one datagram in chunks that the Python client pulls (docs/rpc.md,
"Large replies"). A scene of 20,000 elements is saved through the client (about 3 MB), and
a SPARQL answer of 1.5 MB, which the server refused before ("add LIMIT and OFFSET"), comes
back whole."""

from __future__ import annotations

import json
import sys
import textwrap

from skillbus import paths

N = 20_000


def scene() -> str:
    lines = ["@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .",
             "@prefix owl: <http://www.w3.org/2002/07/owl#> .",
             "@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .",
             "@prefix xsd: <http://www.w3.org/2001/XMLSchema#> .",
             'skiros:Table-1 a skiros:Table, owl:NamedIndividual ; rdfs:label "table" .']
    for j in range(2, N + 1):
        lines.append(f'skiros:Cube-{j} a skiros:Cube, owl:NamedIndividual ; rdfs:label "cube number {j}" ; '
                     f'skiros:PositionX "{j * 0.001}"^^xsd:float .')
        lines.append(f"skiros:Table-1 skiros:contain skiros:Cube-{j} .")
    return "\n".join(lines) + "\n"


CLIENT = textwrap.dedent("""
    import json, sys
    from skillbus.bus import open_bus
    from skillbus.world import WorldModelInterface
    wmi = WorldModelInterface(open_bus(), "big-replies", timeout=30)
    saved = wmi.save_scene()
    rows = wmi.query_ontology("SELECT ?x ?l WHERE { ?x rdfs:label ?l }")
    print(json.dumps({"saved_bytes": len(saved), "individuals": saved.count("owl:NamedIndividual"),
                      "last": "skiros:Cube-%d" % int(sys.argv[1]) in saved, "rows": len(rows),
                      "row": sorted(rows)[0]}))
""")


def test_large_replies_arrive_whole(sandbox, tmp_path):
    path = tmp_path / "big.ttl"
    path.write_text(scene())
    wm = sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", str(tmp_path / "wm"),
                              "--scene", str(path)])
    wm.wait_for("serving", 120)
    p = sandbox.start("client", [sys.executable, "-c", CLIENT, str(N)])
    assert sandbox.wait(p, 180) == 0, p.stderr()
    r = json.loads(p.stdout().strip().splitlines()[-1])
    assert r["saved_bytes"] > 2_000_000 and r["individuals"] == N and r["last"], r
    assert r["rows"] == N and r["row"] == "skiros:Cube-10 cube number 10 ", r
