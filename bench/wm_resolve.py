"""Benchmark: resolving full elements of a type, against SkiROS2's own code path, as the
world grows (1,000 to 100,000 products).

Ours: a Python client (WorldModelInterface) of a wm_server over LCM, in a private network
namespace: how long its replica takes to build (the snapshot, read in pages), then
`resolve_elements(Element("skiros:Product"))` (full elements: type, label, properties,
relations; answered from the replica), the same with one property read from each
element, and `get_element` of an element with 10,000 relations. The ids-only query of
the server is kept beside rdflib's SPARQL for the same ids.

The anchor, in process, does what SkiROS2's world model server does for resolve_elements
(skiros2_world_model core/world_model.py, read for this, not copied): the subclasses by
SPARQL `rdfs:subClassOf*` on its rdflib graph, the subjects of each type, and for each an
element built by triple lookups (every predicate-object of the subject, the predicate's
owl:DatatypeProperty / owl:ObjectProperty type looked up, and every subject-predicate
pointing at it), then cached: "cold" builds them, "warm" is SkiROS2 answering again from
its cache (the callers then share the cached objects). SkiROS2's ROS transport (one
message of every element to the client) is not counted: the anchor is its in-process cost.

Prints the figures per size, the targets (issue "Performance") with met / NOT met, and
writes docs/images/bench_wm_resolve.png (matplotlib).

Run: .venv/bin/python bench/wm_resolve.py [--sizes 1000,5000,10000,100000]   (in `make bench`)
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

from plots import IMAGES
from skillbus import paths
from skillbus.netns import Sandbox, last_json

HERE = Path(__file__).resolve().parent
ONTOLOGY = HERE.parent / "wm_server" / "ontology" / "skiros.ttl"
PLOT = IMAGES / "bench_wm_resolve.png"
BIG_RELATIONS = 10_000
TARGET_HITS = 5_000

def make_scene(products: int) -> str:
    """wm_query's scene (a root, 100 places, products with a label, a pose and a size) with
    `products` products, and an inventory that has (skiros:hasA) up to 10,000 of them."""
    from wm_query import make_scene as places_and_products
    first = 101  # (wm_query's products are numbered from 101; product j is a cube, a cylinder or a starter by j % 3)
    kinds = ["Cube", "Cylinder", "Starter"]
    lines = [places_and_products(first + products),
             'skiros:Inventory-1 a skiros:Location, owl:NamedIndividual ; rdfs:label "inventory" .']
    lines += [f"skiros:Inventory-1 skiros:hasA skiros:{kinds[j % 3]}-{j} ."
              for j in range(first, first + min(products, BIG_RELATIONS))]
    return "\n".join(lines) + "\n"

CLIENT = r'''
import json, sys, time, statistics
from skillbus.bus import open_bus
from skillbus.msgs import wm_query_t
from skillbus.world import Element, WorldModelInterface
from skillbus.world.client import query_all
scene, repeats = sys.argv[1], int(sys.argv[2])
WorldModelInterface(open_bus(), "loader").load_scene(name=scene)  # (on the server: 100k elements are over 16 MiB of text)
out = {}
t = time.perf_counter()
w = WorldModelInterface(open_bus(), "bench")
w.get_element("skiros:Scene-0")
out["replica"] = time.perf_counter() - t
def timed(fn, n):
    xs = []
    for _ in range(n):
        t = time.perf_counter(); r = fn(); xs.append(time.perf_counter() - t)
    return xs, r
product = Element("skiros:Product")
first, found = timed(lambda: w.resolve_elements(product), 1)
out["resolve_first"] = first[0]
out["resolve"], found = timed(lambda: w.resolve_elements(product), repeats)
out["hits"] = len(found)
out["resolve_read"], _ = timed(lambda: [e.getProperty("skiros:PositionX").value for e in w.resolve_elements(product)], repeats)
out["big"], big = timed(lambda: w.get_element("skiros:Inventory-1"), 20)
out["big_relations"], rels = timed(lambda: w.get_element("skiros:Inventory-1").getRelations(), 5)
out["big_count"] = len(rels)
q = wm_query_t(); q.type = "skiros:Product"; q.ids_only = True
out["ids"], ids = timed(lambda: query_all(lambda req, t: w._call_elements("query", req, t), q, timeout=60), repeats)
out["ids_count"] = len(ids)
print(json.dumps(out))
'''


def anchor(scene: str, repeats: int) -> dict:
    """SkiROS2's resolve_elements path on an rdflib graph of the same scene (see the
    module's docstring)."""
    import rdflib
    from rdflib import OWL, RDF, RDFS
    from rdflib.plugins.sparql import prepareQuery
    from skillbus.world import Element

    g = rdflib.Graph()
    t = time.perf_counter()
    g.parse(data=ONTOLOGY.read_text(), format="turtle")
    g.parse(data=scene, format="turtle")
    parse = time.perf_counter() - t
    ns = "http://rvmi.aau.dk/ontologies/skiros.owl#"
    short = {ns: "skiros:", str(RDFS): "rdfs:", str(RDF): "rdf:", str(OWL): "owl:",
             "http://www.w3.org/2001/XMLSchema#": "xsd:"}

    def light(uri) -> str:
        s = str(uri)
        for full, prefix in short.items():
            if s.startswith(full):
                return prefix + s[len(full):]
        return s

    subclasses = prepareQuery("SELECT ?x WHERE { ?x rdfs:subClassOf* ?c }", initNs={"rdfs": RDFS})

    def individual(subject) -> Element:
        e = Element()
        for pred, obj in g.predicate_objects(subject):
            kinds = set(g.objects(pred, RDF.type))
            if OWL.DatatypeProperty in kinds:
                e.setProperty(light(pred), obj.toPython(), light(obj.datatype), force_convertion=True)
            elif OWL.ObjectProperty in kinds:
                e.addRelation("-1", light(pred), light(obj))
            elif pred == RDF.type and obj != OWL.NamedIndividual:
                e._type = light(obj)
            elif pred == RDFS.label:
                e._label = str(obj)
        for subj, pred in g.subject_predicates(subject):
            if light(pred) != "skiros:hasTemplate":
                e.addRelation(light(subj), light(pred), "-1")
        e._id = light(subject)
        return e

    cache: dict = {}

    def get_element(subject) -> Element:
        got = cache.get(subject)
        if got is None:
            got = cache[subject] = individual(subject)
        return got

    def resolve(concept: str) -> list:
        out = []
        for row in g.query(subclasses, initBindings={"c": rdflib.URIRef(ns + concept)}):
            for subj in g.subjects(RDF.type, row[0]):
                out.append(get_element(subj))
        return out

    t = time.perf_counter()
    found = resolve("Product")
    cold = time.perf_counter() - t
    warm = []
    for _ in range(repeats):
        t = time.perf_counter()
        resolve("Product")
        warm.append(time.perf_counter() - t)
    inventory = rdflib.URIRef(ns + "Inventory-1")
    t = time.perf_counter()
    big = individual(inventory)
    big_cold = time.perf_counter() - t
    ids_query = prepareQuery("SELECT ?x WHERE { ?x a ?t . ?t rdfs:subClassOf* skiros:Product }",
                             initNs={"rdfs": RDFS, "skiros": rdflib.Namespace(ns)})
    sparql = []
    for _ in range(max(1, repeats // 2)):
        t = time.perf_counter()
        ids = list(g.query(ids_query))
        sparql.append(time.perf_counter() - t)
    return {"parse": parse, "cold": cold, "warm": warm, "hits": len(found), "big_cold": big_cold,
            "big_count": len(big.getRelations()), "sparql": sparql, "sparql_count": len(ids)}


def median(xs) -> float:
    return statistics.median(xs) if isinstance(xs, list) else xs


def ours(scene: str, repeats: int) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        scenes = Path(tmp) / "data" / "scenes"
        scenes.mkdir(parents=True)
        (scenes / "bench.ttl").write_text(scene)
        with Sandbox() as box:
            server = box.start("wm", [paths.build_dir() / "wm_server" / "wm_server", "--wall-clock",
                                      "--data", Path(tmp) / "data"])
            server.wait_for("serving", 60)
            client = box.start("client", [sys.executable, "-c", CLIENT, "bench", str(repeats)])
            box.wait(client, 1200)
            got = last_json(client.stdout())
            if got is None:
                raise SystemExit(f"the client failed: {client.stderr()[-3000:]}\n{server.stderr()[-2000:]}")
            return got


def plot(rows: list[dict]) -> None:
    from plots import figure  # (matplotlib is loaded only to draw)
    n = [r["n"] for r in rows]
    with figure(PLOT, "Resolving every product of the world", "products resolved (full elements)", "ms (median)",
                log_x=True, log_y=True) as ax:
        for key, label, style in (("resolve", "skillbus resolve_elements (replica)", "o-"),
                                  ("resolve_read", "skillbus, and a property of each read", "o--"),
                                  ("anchor_cold", "SkiROS2 path, rdflib (builds elements)", "s-"),
                                  ("anchor_warm", "SkiROS2 path, rdflib (from its cache)", "s--"),
                                  ("replica", "skillbus: a new replica (snapshot)", "^:")):
            ax.plot(n, [r[key] * 1e3 for r in rows], style, label=label)

def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1000,5000,10000,100000", help="products per world, comma-separated")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-plot", action="store_true")
    args = ap.parse_args()
    rows = []
    print("products  ours: replica  resolve  +read  10k-rel get  ids query | SkiROS2 path: cold  warm  10k-rel  "
          "SPARQL ids | cold/ours   (ms, medians)")
    for n in (int(x) for x in args.sizes.split(",")):
        scene = make_scene(n)
        o = ours(scene, args.repeats)
        a = anchor(scene, args.repeats)
        assert o["hits"] == a["hits"] == n, (o["hits"], a["hits"], n)
        assert o["big_count"] == a["big_count"], (o["big_count"], a["big_count"])
        row = {"n": n, "replica": o["replica"], "resolve": median(o["resolve"]), "resolve_read": median(o["resolve_read"]),
               "big": median(o["big"]), "big_relations": median(o["big_relations"]), "ids": median(o["ids"]),
               "anchor_cold": a["cold"], "anchor_warm": median(a["warm"]), "anchor_big": a["big_cold"],
               "sparql": median(a["sparql"]), "big_count": o["big_count"]}
        rows.append(row)
        print(f"{n:>8}  {row['replica'] * 1e3:>13.0f}  {row['resolve'] * 1e3:>7.1f}  {row['resolve_read'] * 1e3:>5.1f}"
              f"  {row['big'] * 1e3:>11.3f}  {row['ids'] * 1e3:>9.1f} | {row['anchor_cold'] * 1e3:>18.0f}"
              f"  {row['anchor_warm'] * 1e3:>4.0f}  {row['anchor_big'] * 1e3:>7.1f}  {row['sparql'] * 1e3:>10.0f}"
              f" | {row['anchor_cold'] / row['resolve']:>9.1f}x")
        print(json.dumps({"bench": "wm_resolve", **row}), file=sys.stderr)
    print(f"(the element with relations has {rows[-1]['big_count']}; get_element then getRelations(): "
          + ", ".join(f"{r['n']}: {r['big_relations'] * 1e3:.1f} ms" for r in rows) + ")")

    def at(n_wanted: int):
        return min(rows, key=lambda r: abs(r["n"] - n_wanted))

    r5 = at(TARGET_HITS)
    ok = r5["resolve"] < 0.025 and r5["anchor_cold"] / r5["resolve"] >= 10
    print(f"target: {r5['n']} full elements resolved under 25 ms and at least 10x faster than SkiROS2's path: "
          f"{'met' if ok else 'NOT met'} ({r5['resolve'] * 1e3:.1f} ms, {r5['anchor_cold'] / r5['resolve']:.1f}x)")
    big = [r for r in rows if r["big_count"] >= BIG_RELATIONS]
    if big:
        b = big[0]
        print(f"target: an element with {b['big_count']} relations read under 1 ms: "
              f"{'met' if b['big'] < 0.001 else 'NOT met'} ({b['big'] * 1e3:.3f} ms)")
    r10 = at(10_000)
    print(f"target: a {r10['n']}-element replica built under 0.5 s: {'met' if r10['replica'] < 0.5 else 'NOT met'} "
          f"({r10['replica']:.2f} s)")
    if not args.no_plot:
        plot(rows)
        print(f"plot: {PLOT.relative_to(HERE.parent)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
