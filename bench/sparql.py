"""Benchmark: SPARQL on the world model server (Rasqal, RPC wm.sparql through the Python
client's query_ontology) against rdflib, the engine SkiROS2's world model runs its
queries on, in the same run, on the same graph: the ontology (wm_server/ontology/skiros.ttl)
and a scene of N elements (bench/wm_query.py's), rdflib holding it parsed in memory as
SkiROS2 does. The same queries, each repeated; medians and the ratio rdflib/ours.

The server re-reads the graph into Rasqal for every query (it caches the graph's Turtle
per world version, not Rasqal's parse): the figure includes that, and grows with the
world.

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
queries, repeats = json.loads(sys.argv[1]), int(sys.argv[2])
# (a slow query is a figure, not a failure: the server's SPARQL reads the whole world
# into Rasqal at every query, and its joins scan; 10,000 elements took over 10 s)
wmi = WorldModelInterface(open_bus(), timeout=600.0)
out = {}
for name, q in queries.items():
    times, rows = [], 0
    for _ in range(repeats):
        t0 = time.perf_counter()
        rows = len(wmi.query_ontology(q))
        times.append((time.perf_counter() - t0) * 1e3)
    out[name] = {"ms": statistics.median(times), "rows": rows}
print(json.dumps(out))
'''


def rdflib_side(scene: Path, repeats: int) -> dict:
    import rdflib
    g = rdflib.Graph()
    g.parse(ONTOLOGY, format="turtle")
    g.parse(scene, format="turtle")
    ns = {p: rdflib.Namespace(str(n)) for p, n in g.namespaces()}
    out = {}
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
        report[n] = {name: {"ours_ms": round(ours[name]["ms"], 2), "rdflib_ms": round(theirs[name]["ms"], 2),
                            "rows": ours[name]["rows"], "rdflib_rows": theirs[name]["rows"],
                            "rdflib_over_ours": round(theirs[name]["ms"] / ours[name]["ms"], 2)}
                     for name in QUERIES}
        print(f"SPARQL, {n} elements, median of {args.repeats} (ms)")
        print(f"{'query':<30} {'wm_server (Rasqal, RPC)':>24} {'rdflib in-process':>18} {'rdflib/ours':>12} {'rows':>6}")
        for name, r in report[n].items():
            same = "" if r["rows"] == r["rdflib_rows"] else f" (rdflib: {r['rdflib_rows']})"
            print(f"{name:<30} {r['ours_ms']:>24.2f} {r['rdflib_ms']:>18.2f} {r['rdflib_over_ours']:>12.2f} "
                  f"{r['rows']:>6}{same}")
    print(json.dumps({"sparql": report}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
