"""Benchmark: SPARQL on the world model server (Rasqal, RPC wm.sparql through the Python
client's query_ontology) against rdflib, the engine SkiROS2's world model runs its
queries on, in the same run, on the same graph: the ontology (wm_server/ontology/skiros.ttl)
and a scene of N elements (bench/wm_query.py's), rdflib holding it parsed in memory as
SkiROS2 does. The same queries, each repeated; medians and the ratio rdflib/ours.

The server makes the world's graph once per world version and keeps it indexed for Rasqal
(wm_server/src/sparql_graph.hpp): the first query after a change pays for that, measured
after the queries (a change, a query, repeated) and printed beside rdflib's parse of the
same graph.

Run: .venv/bin/python bench/sparql.py [--sizes 1000,10000] [--repeats 20]
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from skillbus import paths  # noqa: E402
from skillbus.netns import Sandbox, last_json  # noqa: E402
from wm_query import ONTOLOGY, make_scene  # noqa: E402

QUERIES = {
    "ontology: direct subclasses": "SELECT ?c WHERE { ?c rdfs:subClassOf skiros:Product }",
    "world: elements of a type": "SELECT ?x WHERE { ?x a skiros:Cube } LIMIT 200",
    "world: what a table holds": "SELECT ?x WHERE { skiros:Table-3 skiros:contain ?x }",
    "world: join and filter": "SELECT ?x ?l WHERE { ?x a skiros:Starter ; rdfs:label ?l ; skiros:PositionX ?p . "
                              "FILTER(?p > 0.03) } LIMIT 100",
}

CLIENT = r'''
import json, sys, time, statistics
from skillbus.bus import open_bus
from skillbus.world import WorldModelInterface
from skillbus.world.element import Element
queries, repeats = json.loads(sys.argv[1]), int(sys.argv[2])
# (a slow query is a figure, not a failure: before the server kept the graph, it read the
# whole world into Rasqal at every query and its joins scanned; 10,000 elements took 10 s)
wmi = WorldModelInterface(open_bus(), timeout=600.0)
wmi.query_ontology("ASK { ?s ?p ?o }")  # (the first query of this world version: reads the graph)
out = {}
for name, q in queries.items():
    times, rows = [], 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        rows = len(wmi.query_ontology(q))
        times.append((time.perf_counter() - t0) * 1e3)
    out[name] = {"ms": statistics.median(times), "rows": rows}
# The first query of a world version makes the graph: one after each of `repeats` changes
# (an element added), after the queries above so that their rows stay rdflib's.
firsts = []
for i in range(repeats):
    wmi.add_element(Element("skiros:Cube", f"bench-{i}"))
    t0 = time.perf_counter()
    wmi.query_ontology("ASK { ?s ?p ?o }")
    firsts.append((time.perf_counter() - t0) * 1e3)
out["_first_query_ms"] = statistics.median(firsts)
print(json.dumps(out))
'''


def rdflib_side(scene: Path, repeats: int) -> dict:
    import rdflib
    t0 = time.perf_counter()
    g = rdflib.Graph()
    g.parse(ONTOLOGY, format="turtle")
    g.parse(scene, format="turtle")
    out: dict = {"_parse_ms": (time.perf_counter() - t0) * 1e3}
    ns = {p: rdflib.Namespace(str(n)) for p, n in g.namespaces()}
    for name, q in QUERIES.items():
        times, rows = [], 0
        for _ in range(repeats):
            t0 = time.perf_counter()
            rows = len(list(g.query(q, initNs=ns)))
            times.append((time.perf_counter() - t0) * 1e3)
        out[name] = {"ms": statistics.median(times), "rows": rows}
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", default="1000,10000")
    ap.add_argument("--repeats", type=int, default=20)
    args = ap.parse_args()
    report = {}
    for n in [int(s) for s in args.sizes.split(",")]:
        with tempfile.TemporaryDirectory() as tmp:
            scene = Path(tmp) / "scene.ttl"
            scene.write_text(make_scene(n))
            with Sandbox() as box:
                wm = box.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", str(Path(tmp) / "wm"),
                                      "--scene", str(scene)])
                wm.wait_for("serving", 120)
                client = box.start("client", [sys.executable, "-c", CLIENT, json.dumps(QUERIES), str(args.repeats)])
                box.wait(client, 1800)
                ours = last_json(client.stdout())
                if ours is None:
                    print(client.stderr()[-2000:], file=sys.stderr)
                    return 1
            theirs = rdflib_side(scene, args.repeats)
        report[n] = {"reading the graph": {"wm_server_first_query_ms": round(ours["_first_query_ms"], 2),
                                           "rdflib_parse_ms": round(theirs["_parse_ms"], 2)}}
        report[n].update({name: {"ours_ms": round(ours[name]["ms"], 2), "rdflib_ms": round(theirs[name]["ms"], 2),
                                 "rows": ours[name]["rows"], "rdflib_rows": theirs[name]["rows"],
                                 "rdflib_over_ours": round(theirs[name]["ms"] / ours[name]["ms"], 2)}
                          for name in QUERIES})
        print(f"SPARQL, {n} elements, median of {args.repeats} (ms)")
        print(f"{'query':<30} {'wm_server (Rasqal, RPC)':>24} {'rdflib in-process':>18} {'rdflib/ours':>12} {'rows':>6}")
        for name, r in report[n].items():
            if name == "reading the graph":
                continue
            same = "" if r["rows"] == r["rdflib_rows"] else f" (rdflib: {r['rdflib_rows']})"
            print(f"{name:<30} {r['ours_ms']:>24.2f} {r['rdflib_ms']:>18.2f} {r['rdflib_over_ours']:>12.2f} "
                  f"{r['rows']:>6}{same}")
        g = report[n]["reading the graph"]
        print(f"reading the graph: the server's first query after a change of the world {g['wm_server_first_query_ms']:.1f}"
              f" ms (median of {args.repeats} changes; it makes the graph once per version); rdflib's parse of the graph "
              f"{g['rdflib_parse_ms']:.1f} ms")
    print(json.dumps({"sparql": report}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
