"""The world model server with a world too large for one reply (a small-scale check of
the mechanisms that bench/wm_scale.py measures at 100,000 elements): a query whose reply
would be too large is refused naming paging, and the Python client pages it to the end;
a new replica of the whole world forms from snapshot pages (a container's thousand
relations do not go into one page); snapshots written in the background while commits
go on leave a data directory that restarts with every commit."""

import sys

from conftest import last_json

PREFIXES = """@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .
@prefix owl: <http://www.w3.org/2002/07/owl#> .
@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .
@prefix xsd: <http://www.w3.org/2001/XMLSchema#> .
"""
PRODUCTS = 3000  # ~300 bytes each: ~0.9 MB as one reply, seven times the bound


def scene(n: int) -> str:
    """Two tables holding n cubes between them (1,500 relations from each table)."""
    lines = [PREFIXES]
    for t in (1, 2):
        lines.append(f'skiros:Table-{t} a skiros:Table, owl:NamedIndividual ; rdfs:label "table{t}" .')
    for j in range(3, n + 3):
        lines.append(f'skiros:Cube-{j} a skiros:Cube, owl:NamedIndividual ; rdfs:label "c{j}" ; '
                     f'skiros:PositionX "{j * 0.001}"^^xsd:float ; skiros:PositionY "0.0"^^xsd:float ; '
                     f'skiros:PositionZ "0.02"^^xsd:float ; skiros:Size "0.05"^^xsd:float .')
        lines.append(f"skiros:Table-{1 + j % 2} skiros:contain skiros:Cube-{j} .")
    return "\n".join(lines) + "\n"


CLIENT = r'''
import json, sys
from skillbus.bus import open_bus
from skillbus.msgs import wm_elements_t, wm_query_t
from skillbus.rpc import RpcClient, RpcRemoteError
from skillbus.world import Element, WorldModelInterface
from skillbus.world.client import query_all
from skillbus.world.wire import decode_elements

rpc = RpcClient(open_bus(), "WM", "scale-test")
out = {}
q = wm_query_t()
q.type = "skiros:Product"
try:
    rpc.call("query", q, wm_elements_t, timeout=10)  # every product at once: refused
    out["refused"] = ""
except RpcRemoteError as e:
    out["refused"] = str(e)
pages = []
def call(req, timeout):
    pages.append(req.limit)
    return decode_elements(rpc.call_raw("query", req.encode(), timeout=timeout))
found = query_all(call, q)
out["paged"] = [e.id for e in found]
out["pages"] = len(pages)
out["first_props"] = {p.key: p.values for p in found[0].properties}
w = WorldModelInterface(open_bus(), "scale-test-replica", timeout=10)
out["replica_elements"] = len(w._elements)
out["replica_relations"] = len(w._relations)
out["resolved"] = len(w.resolve_elements(Element("skiros:Cube")))
out["on_table1"] = len(w.get_relations(subj="skiros:Table-1", pred="skiros:contain"))
for i in range(int(sys.argv[1])):  # a snapshot every 40 commits (--snapshot-every), written in the background
    e = w.get_element(f"skiros:Cube-{3 + i}")
    e.label = f"moved{i}"
    w.update_element(e)
out["version"] = w.version
print(json.dumps(out))
'''


def ids_in_order(n: int) -> list[str]:
    return sorted(f"skiros:Cube-{j}" for j in range(3, n + 3))


def test_a_large_query_is_refused_whole_paged_by_the_client_and_a_replica_forms(sandbox, tmp_path):
    from skillbus import paths
    (tmp_path / "scene.ttl").write_text(scene(PRODUCTS))
    data = tmp_path / "data"
    args = [paths.binary("wm_server"), "--wall-clock", "--data", data, "--snapshot-every", "40"]
    server = sandbox.start("wm", [*args, "--scene", tmp_path / "scene.ttl"])
    server.wait_for("serving", 60)
    commits = 300
    client = sandbox.start("client", [sys.executable, "-c", CLIENT, str(commits)])
    assert sandbox.wait(client, 180) == 0, client.stderr()[-3000:]
    out = last_json(client.stdout())
    assert "the reply of 3000 elements would be larger than 131072 bytes" in out["refused"], out["refused"]
    assert "ask for it in pages" in out["refused"]
    assert out["paged"] == ids_in_order(PRODUCTS)  # every product once, in id order
    assert out["pages"] == PRODUCTS // 200 + 1
    assert out["first_props"]["skiros:Size"] == [0.05]
    assert out["replica_elements"] == PRODUCTS + 2 and out["replica_relations"] == PRODUCTS
    assert out["resolved"] == PRODUCTS and out["on_table1"] == PRODUCTS // 2
    assert out["version"] == 1 + commits
    assert server.returncode is None
    # The commits made snapshots in the background (every 40); the server restarts from
    # the last one and the journal after it with every commit.
    sandbox.kill(server, 15)
    assert sandbox.wait(server, 30) == 0, server.stderr()[-2000:]
    restarted = sandbox.start("wm-restarted", args)
    started = restarted.wait_for("serving", 60)
    line = restarted.stderr()[started.start():].splitlines()[0]
    assert f"version {1 + commits}, {PRODUCTS + 2} elements (snapshot at version" in line, line
    check = sandbox.start("check", [sys.executable, "-c",
                                    "import json; from skillbus.bus import open_bus; "
                                    "from skillbus.world import WorldModelInterface; "
                                    "w = WorldModelInterface(open_bus(), 'check', timeout=10); "
                                    "print(json.dumps({'moved': sum(e.label.startswith('moved') "
                                    "for e in w._elements.values()), 'version': w.version}))"])
    assert sandbox.wait(check, 60) == 0, check.stderr()[-2000:]
    assert last_json(check.stdout()) == {"moved": commits, "version": 1 + commits}


def test_the_wire_decoder_reads_what_lcm_reads():
    """skillbus.world.wire decodes a page as LCM's generated Python plus element_from_msg
    does: every value type, strings with and without text, several values, no values."""
    import pytest
    from skillbus.msgs import wm_elements_t, wm_element_t, wm_property_t, wm_relation_t, wm_value_t
    from skillbus.world.convert import element_from_msg
    from skillbus.world.wire import decode_elements

    def value(kind, **kw):
        v = wm_value_t()
        v.type = kind
        for k, x in kw.items():
            setattr(v, k, x)
        return v

    m = wm_elements_t()
    m.version, m.next_id, m.total = 7, 42, 3
    props = {"skiros:PositionX": [value(wm_value_t.FLOAT, f=0.25)],
             "skiros:Name": [value(wm_value_t.STRING, s="grün"), value(wm_value_t.STRING, s="")],
             "skiros:Count": [value(wm_value_t.INT, i=-(2 ** 40))],
             "skiros:Flag": [value(wm_value_t.BOOL, b=True), value(wm_value_t.BOOL, b=False)],
             "skiros:Empty": []}
    for n in range(3):
        e = wm_element_t()
        e.id, e.type, e.label = f"skiros:Cube-{n}", "skiros:Cube", f"c{n}" if n else ""
        for key, values in props.items():
            p = wm_property_t()
            p.key, p.values, p.num_values = key, values, len(values)
            e.properties.append(p)
        e.num_properties = len(e.properties)
        m.elements.append(e)
    m.num_elements = 3
    r = wm_relation_t()
    r.subject, r.predicate, r.object = "skiros:Cube-0", "skiros:contain", "skiros:Cube-1"
    m.relations, m.num_relations = [r], 1
    data = m.encode()
    page = decode_elements(data)
    assert (page.version, page.next_id, page.total) == (7, 42, 3)
    assert page.elements == [element_from_msg(e) for e in m.elements]
    assert [type(v) for v in page.elements[0].getProperty("skiros:Flag").values] == [bool, bool]
    assert page.relations == [("skiros:Cube-0", "skiros:contain", "skiros:Cube-1")]
    with pytest.raises(ValueError):
        decode_elements(data[:-3])
    with pytest.raises(ValueError):
        decode_elements(b"\0" * 8 + data[8:])
