"""The world model server as a process: its API through the Python client, bad input,
a crash in the middle of 2,000 writes, and determinism under lockstep."""

import json
import random
import re
import signal
import sys
from pathlib import Path

import pytest

from conftest import last_json, python_tool
from skillbus.waiting import wait_until

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "deploy" / "scenes" / "demo.ttl"


def start_server(sandbox, binary_path, data, *extra, name="wm"):
    return sandbox.start(name, [binary_path, "--wall-clock", "--data", data, "--scene", SCENE, *extra])


def wm_binary():
    from skillbus import paths
    return paths.binary("wm_server")


def run_scenario(sandbox, name, *args, timeout=120):
    p = sandbox.start(f"scenario-{name}", python_tool("wm_scenarios.py", name, *map(str, args)))
    rc = sandbox.wait(p, timeout)
    assert rc == 0, f"scenario {name} failed:\n{p.stderr()[-3000:]}"
    return last_json(p.stdout())


def probe_world(sandbox, server, fields: str) -> dict:
    """What a new client sees of the world: `fields`, a Python dict expression over the
    client `w` (a WorldModelInterface), printed as JSON by a process in the sandbox."""
    code = ("import json; from skillbus.bus import open_bus; from skillbus.world import WorldModelInterface; "
            f"w = WorldModelInterface(open_bus(), 'probe'); print(json.dumps({fields}))")
    probe = sandbox.start(f"probe-{len(sandbox.procs)}", [sys.executable, "-c", code])
    assert sandbox.wait(probe, 60) == 0, probe.stderr()[-2000:] + server.stderr()[-2000:]
    return last_json(probe.stdout())


def test_api_through_the_python_client(sandbox, tmp_path):
    server = start_server(sandbox, wm_binary(), tmp_path / "data")
    assert run_scenario(sandbox, "api")["ok"]
    assert server.returncode is None


def test_bad_input_gets_named_errors_and_changes_nothing(sandbox, tmp_path):
    server = start_server(sandbox, wm_binary(), tmp_path / "data")
    assert run_scenario(sandbox, "bad_input")["ok"]
    assert server.returncode is None, server.stderr()[-2000:]


def test_scene_files_are_named_never_paths_and_stay_in_the_data_directory(sandbox, tmp_path):
    import stat
    data = tmp_path / "data"
    server = start_server(sandbox, wm_binary(), data)
    assert run_scenario(sandbox, "scene_files", data)["ok"]
    saved = data / "scenes" / "snap-1.ttl"
    assert saved.exists() and stat.S_IMODE(saved.stat().st_mode) == 0o600
    assert sorted(p.name for p in data.iterdir()) == ["journal.bin", "lock", "scenes", "snapshot.bin"], \
        "nothing was written outside DATA/scenes"
    assert server.returncode is None


def test_kill_9_during_2000_writes_loses_and_duplicates_nothing(sandbox, tmp_path):
    data = tmp_path / "data"
    server = start_server(sandbox, wm_binary(), data, "--snapshot-every", "300")
    writer = sandbox.start("writer", python_tool("wm_scenarios.py", "writer", "2000"))
    kill_after_acks = random.Random().randrange(200, 1800)  # a random moment, printed on failure

    def acked() -> bool:
        if writer.stdout().count("ack ") >= kill_after_acks:
            return True
        assert writer.returncode is None, writer.stderr()[-2000:]
        return False

    wait_until(acked, 120, f"{kill_after_acks} acks of the writer (it made no progress)", interval=0.01)
    sandbox.kill(server, signal.SIGKILL)
    sandbox.wait(server, 10)
    acked_before_kill = writer.stdout().count("ack ")
    restarted = start_server(sandbox, wm_binary(), data, "--snapshot-every", "300", name="wm-restarted")
    assert sandbox.wait(writer, 180) == 0, f"killed after {kill_after_acks} acks: {writer.stderr()[-2000:]}"
    assert last_json(writer.stdout())["written"] == 2000
    probe = run_scenario_probe(sandbox)
    labels = probe["labels"]
    missing = [i for i in range(2000) if labels.get(f"w{i}", 0) == 0]
    duplicated = [i for i in range(2000) if labels.get(f"w{i}", 0) > 1]
    assert not missing and not duplicated, (kill_after_acks, acked_before_kill, missing[:10], duplicated[:10])
    assert probe["version"] == 1 + 2000  # the scene load, then one version per write
    assert "replayed" in restarted.stderr() or "snapshot" in restarted.stderr()


def test_a_commit_made_durable_but_never_acknowledged_is_not_applied_twice(sandbox, tmp_path):
    # The server dies right after the journal has commit 700 and before it replies; the
    # writer's retry reaches the restarted server, which must answer from its recovered
    # memory of transactions instead of applying the write again.
    data = tmp_path / "data"
    server = start_server(sandbox, wm_binary(), data, "--snapshot-every", "300", "--crash-after-commits", "700")
    writer = sandbox.start("writer", python_tool("wm_scenarios.py", "writer", "1000"))
    assert sandbox.wait(server, 60) == 137
    assert "crashing on purpose after 700 commits" in server.stderr()
    start_server(sandbox, wm_binary(), data, "--snapshot-every", "300", name="wm-restarted")
    assert sandbox.wait(writer, 120) == 0, writer.stderr()[-2000:]
    labels = run_scenario_probe(sandbox)["labels"]
    assert len(labels) == 1000 and set(labels.values()) == {1}
    assert labels["w699"] == 1


def run_scenario_probe(sandbox):
    code = ("import json, collections; from skillbus.bus import open_bus; "
            "from skillbus.world import WorldModelInterface; w = WorldModelInterface(open_bus(), 'probe'); "
            "print(json.dumps({'version': w.version, 'labels': collections.Counter("
            "e.label for e in w.get_elements() if e.label.startswith('w'))}))")
    import sys
    p = sandbox.start("probe", [sys.executable, "-c", code])
    assert sandbox.wait(p, 60) == 0, p.stderr()[-2000:]
    return last_json(p.stdout())


def lockstep_run(sandbox_factory, tmp_path, tag, frames=300):
    from skillbus import paths
    with sandbox_factory(log_dir=tmp_path / tag) as box:
        clock = box.start("clock", [paths.binary("sb_clock"), "--frames", str(frames), "--participants", "wm,writer"])
        server = box.start("wm", [wm_binary(), "--data", tmp_path / tag / "data", "--scene", SCENE, "--name", "wm"])
        writer = box.start("writer", python_tool("wm_scenarios.py", "lockstep_writer", str(frames)))
        assert box.wait(clock, 120) == 0, clock.stdout() + clock.stderr()[-2000:]
        assert box.wait(server, 30) == 0, server.stderr()[-2000:]
        assert box.wait(writer, 30) == 0, writer.stderr()[-2000:]
        return last_json(clock.stdout()), last_json(server.stdout()), last_json(writer.stdout())


def test_two_lockstep_runs_of_the_same_writes_give_the_same_world_and_digest(tmp_path):
    from skillbus.netns import Sandbox
    a = lockstep_run(Sandbox, tmp_path, "a")
    b = lockstep_run(Sandbox, tmp_path, "b")
    assert a[0]["frames"] == 300
    assert a[1]["version"] > 100  # the script really wrote
    assert a[1]["version"] == b[1]["version"] and a[1]["elements"] == b[1]["elements"]
    assert a[0]["digest"] == b[0]["digest"]
    assert a[2]["version"] == a[1]["version"] - 0 or a[2]["version"] <= a[1]["version"]


def test_cli_get_query_tree_save_load(sandbox, tmp_path):
    import sys
    start_server(sandbox, wm_binary(), tmp_path / "data")

    def cli(*args):
        p = sandbox.start(f"cli-{args[0]}-{len(sandbox.procs)}", [sys.executable, "-m", "skillbus.cli", "wm", *map(str, args)])
        rc = sandbox.wait(p, 60)
        return rc, p.stdout(), p.stderr()

    rc, out, _ = cli("get", "skiros:Cube-2")
    assert rc == 0 and "label='red'" in out and "skiros:PositionZ = 0.425" in out
    rc, out, _ = cli("query", "--type", "skiros:Product")
    assert rc == 0 and "3 element(s)" in out
    rc, out, _ = cli("tree")
    assert rc == 0 and "  skiros:Table-1 [table] at (0.500, 0.000, 0.000)" in out
    assert "    skiros:Cube-2 [red] at (-0.100, 0.150, 0.425)" in out
    rc, out, _ = cli("save", tmp_path / "saved.ttl")
    assert rc == 0 and (tmp_path / "saved.ttl").read_text().count("owl:NamedIndividual") == 10  # the demo's nine elements and the scene
    rc, out, _ = cli("load", tmp_path / "saved.ttl")
    assert rc == 0 and "10 elements" in out  # the scene and its nine
    rc, _, err = cli("get", "skiros:Nope-1")
    assert rc == 1 and "no element skiros:Nope-1" in err
    (tmp_path / "broken.ttl").write_text("this is not turtle")
    rc, _, err = cli("load", tmp_path / "broken.ttl")
    assert rc == 1 and "malformed Turtle" in err


def test_a_scene_load_that_cannot_be_made_durable_changes_nothing(sandbox, tmp_path):
    # Before, the world went on at the new scene's version with no journal record of it:
    # the commits after were acknowledged, and a restart refused the journal (a gap in
    # its versions) so that `wm repair` dropped them.
    data = tmp_path / "data"
    server = start_server(sandbox, wm_binary(), data)
    r = run_scenario(sandbox, "failed_load", data)
    assert r["labels"] == ["after-load", "before-load"] and r["version"] == r["version_before"] + 1, r
    sandbox.kill(server, signal.SIGTERM)
    assert sandbox.wait(server, 20) == 0, server.stderr()[-2000:]
    again = start_server(sandbox, wm_binary(), data, name="wm-again")
    seen = probe_world(sandbox, again, "{'version': w.version, 'labels': "
                       "sorted(e.label for e in w.get_elements() if e.label.endswith('-load'))}")
    assert seen == {"version": r["version"], "labels": r["labels"]}, (seen, r)
    assert again.returncode is None


def test_a_scene_load_whose_journal_cannot_be_restarted_takes_no_commit_until_a_restart(sandbox, tmp_path):
    # The new scene's snapshot is in place, its new journal is not: the old journal must
    # take no more records (the snapshot would hide them), and a restart has the new scene.
    data = tmp_path / "data"
    server = start_server(sandbox, wm_binary(), data)
    r = run_scenario(sandbox, "journal_switch_fails", data)
    sandbox.kill(server, signal.SIGTERM)
    sandbox.wait(server, 20)
    (data / "journal.bin.tmp").rmdir()
    again = start_server(sandbox, wm_binary(), data, name="wm-again")
    seen = probe_world(sandbox, again, "{'version': w.version, 'labels': "
                       "sorted(e.label for e in w.get_elements() if e.label in ('before-load', 'after'))}")
    assert seen == {"version": r["version_before"] + 1, "labels": []}, (seen, r)


@pytest.mark.parametrize("change", ["load", "axioms"])
def test_a_crash_between_a_scene_changes_files_and_its_snapshot_leaves_the_old_scene_whole(sandbox, tmp_path, change):
    # A scene load (or new axioms) writes the scene's side files, then its snapshot. Before,
    # a crash in between restarted with the new scene's classes and axioms beside the old
    # world: a scene that was never acknowledged, half in force.
    data = tmp_path / "data"
    server = start_server(sandbox, wm_binary(), data)
    client = sandbox.start("change-blocked", python_tool("wm_scenarios.py", "change_blocked", str(data), change))
    before = json.loads(client.wait_for(re.compile(r'\{"version_before": \d+\}'), 60, stream="stdout").group(0))

    def new_scene_files_written() -> bool:
        return any("Widget" in f.read_text(errors="replace") for f in data.glob("scene_extra*.ttl"))
    wait_until(new_scene_files_written, 30, "the scene change's side files")
    sandbox.kill(server)  # SIGKILL: the snapshot is blocked on a FIFO nobody reads
    sandbox.wait(server, 20)
    sandbox.kill(client)
    sandbox.wait(client, 20)
    again = start_server(sandbox, wm_binary(), data, name="wm-again")
    seen = probe_world(sandbox, again, "{'version': w.version, 'widget': 'Widget' in w.save_scene(), "
                       "'labels': sorted(e.label for e in w.get_elements() if e.label == 'before-change')}")
    assert seen == {"version": before["version_before"], "widget": False, "labels": ["before-change"]}, (seen, before)
    assert not [f.name for f in data.glob("scene_*") if str(before["version_before"] + 1) in f.name]
    assert again.returncode is None


def test_new_axioms_that_cannot_be_made_durable_change_nothing(sandbox, tmp_path):
    # Before, the axioms were in force (and in the side file) at a version no snapshot or
    # journal record explained.
    data = tmp_path / "data"
    server = start_server(sandbox, wm_binary(), data)
    r = run_scenario(sandbox, "failed_axioms", data)
    assert r["unchanged"] == {"version": r["version_before"], "widget": False}, r
    assert r["version_after_commit"] == r["version_before"] + 1, r
    assert server.returncode is None


def test_a_request_larger_than_a_receiver_takes_fails_at_once_naming_the_limit(transport_sandbox, tmp_path):
    # Before, a 17 MiB scene text went out, every receiver dropped it (LCM reassembles at
    # most 16 MiB), and the call timed out saying nothing of why. DDS refuses it too: a
    # program that works on one transport works on the other.
    sandbox = transport_sandbox
    server = start_server(sandbox, wm_binary(), tmp_path / "data")
    code = ("import json, time; from skillbus.bus import open_bus, BusError; "
            "from skillbus.world import WorldModelInterface; w = WorldModelInterface(open_bus(), 'big'); "
            "t = time.monotonic()\n"
            "try:\n    w.load_scene(turtle='#' * (17 << 20)); print(json.dumps({'error': ''}))\n"
            "except BusError as e:\n    print(json.dumps({'error': str(e), 's': time.monotonic() - t, "
            "'version': w.version}))")
    probe = sandbox.start("big", [sys.executable, "-c", code])
    assert sandbox.wait(probe, 60) == 0, probe.stderr()[-2000:]
    r = last_json(probe.stdout())
    assert "bytes on SB_WM_REQ: over the 16777216 bytes (16 MiB) a receiver reassembles" in r["error"], r
    assert r["s"] < 2.0 and r["version"] >= 1, r
    assert server.returncode is None
    # What the error and the docs advise: the scene in the server's folder, loaded by name.
    (tmp_path / "data" / "scenes").mkdir(exist_ok=True)
    (tmp_path / "data" / "scenes" / "big.ttl").write_text(
        "@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .\n"
        "@prefix owl: <http://www.w3.org/2002/07/owl#> .\n@prefix rdfs: <http://www.w3.org/2000/01/rdf-schema#> .\n"
        + "# padding\n" * (2 << 20) +
        "skiros:Product-900 a skiros:Product, owl:NamedIndividual ; rdfs:label \"by-name\" .\n")
    code = ("import json; from skillbus.bus import open_bus; from skillbus.world import WorldModelInterface; "
            "w = WorldModelInterface(open_bus(), 'big'); w.load_scene(name='big'); "
            "print(json.dumps({'labels': sorted(e.label for e in w.get_elements())}))")
    probe = sandbox.start("by-name", [sys.executable, "-c", code])
    assert sandbox.wait(probe, 60) == 0, probe.stderr()[-2000:]
    assert "by-name" in last_json(probe.stdout())["labels"], probe.stdout()[-2000:]
    # A name that is a path, or names no scene, is refused naming it; the world stays.
    code = ("import json; from skillbus.bus import open_bus; from skillbus.world import WorldModelInterface\n"
            "w = WorldModelInterface(open_bus(), 'bad'); out = {}\n"
            "for name in ('../journal', '/etc/passwd', 'missing'):\n"
            "    try:\n        w.load_scene(name=name); out[name] = 'loaded'\n"
            "    except Exception as e:\n        out[name] = f'{type(e).__name__}: {e}'\n"
            "out['labels'] = sorted(e.label for e in w.get_elements())\nprint(json.dumps(out))")
    probe = sandbox.start("bad-names", [sys.executable, "-c", code])
    assert sandbox.wait(probe, 60) == 0, probe.stderr()[-2000:]
    bad = last_json(probe.stdout())
    for name in ("../journal", "/etc/passwd", "missing"):
        assert bad[name].startswith("WorldModelError") and "scene" in bad[name], bad
    assert "by-name" in bad["labels"], bad
    cli = sandbox.start("cli", [sys.executable, "-m", "skillbus.cli", "wm", "load", "--on-server", "big"])
    assert sandbox.wait(cli, 60) == 0, cli.stderr()[-2000:]
    assert "loaded big: version" in cli.stdout(), cli.stdout()
    cli = sandbox.start("cli-bad", [sys.executable, "-m", "skillbus.cli", "wm", "load", "--on-server", "../big"])
    assert sandbox.wait(cli, 60) != 0
    assert "scene" in cli.stderr() and "Traceback" not in cli.stderr(), cli.stderr()[-2000:]


@pytest.mark.parametrize("value, why", [('"NaN"^^xsd:float', "is not a finite number"),
                                        ('"INF"^^xsd:float', "is not a finite number"),
                                        ('"1e999"^^xsd:float', "is not a finite number"),
                                        ('"99999999999999999999"^^xsd:int', "is beyond a 64-bit integer")],
                         ids=["nan", "inf", "overflow", "int-overflow"])
def test_a_scene_with_a_value_a_commit_would_refuse_is_refused_and_changes_nothing(sandbox, tmp_path, value, why):
    # Before, a scene's NaN, infinity or out-of-range number was stored (only commits were
    # checked): it reached the skill manager's replica, which then refused every read of
    # the world, so that every task failed with "no world model".
    import sys
    start_server(sandbox, wm_binary(), tmp_path / "data")

    def cli(*args):
        p = sandbox.start(f"cli-{args[0]}-{len(sandbox.procs)}", [sys.executable, "-m", "skillbus.cli", "wm", *map(str, args)])
        return sandbox.wait(p, 60), p.stdout(), p.stderr()

    bad = tmp_path / "bad.ttl"
    bad.write_text(SCENE.read_text().replace('skiros:PositionZ "0.425"^^xsd:float', f"skiros:PositionZ {value}", 1))
    assert bad.read_text() != SCENE.read_text()
    rc, out, err = cli("load", bad)
    assert rc == 1 and why in err and "PositionZ" in err, (rc, out, err)
    rc, out, err = cli("get", "skiros:Cube-2")  # the world as it was
    assert rc == 0 and "skiros:PositionZ = 0.425" in out, out + err
    # and at start: the server names it and does not start
    refused = sandbox.start("wm-bad", [wm_binary(), "--wall-clock", "--data", tmp_path / "other", "--scene", bad])
    assert sandbox.wait(refused, 30) != 0
    assert why in refused.stderr(), refused.stderr()


UNKNOWN_RELATION_PROBE = r'''
import json
from skillbus.bus import open_bus
from skillbus.msgs import wm_elements_t, wm_query_t, wm_relation_t, wm_value_t
from skillbus.rpc import RpcClient, RpcRemoteError
rpc = RpcClient(open_bus(), "WM", "probe")
def query(predicate):
    q = wm_query_t(); q.type = "skiros:Product"
    r = wm_relation_t(); r.subject, r.predicate, r.object = "*", predicate, ""
    q.relations, q.num_relations = [r], 1
    try:
        return {"ids": sorted(e.id for e in rpc.call("query", q, wm_elements_t, timeout=10).elements)}
    except RpcRemoteError as e:
        return {"refused": str(e)}
def may_relate(predicate):
    r = wm_relation_t(); r.subject, r.predicate, r.object = "skiros:Table", predicate, "skiros:Cube"
    try:
        return {"b": bool(rpc.call("may_relate", r, wm_value_t, timeout=10).b)}
    except RpcRemoteError as e:
        return {"refused": str(e)}
print(json.dumps({"contain": query("skiros:contain"), "misspelt": query("skiros:contian"), "any": query("*"),
                  "may": may_relate("skiros:contain"), "may_misspelt": may_relate("skiros:contian")}))
'''


def test_a_query_naming_a_relation_type_the_ontology_lacks_is_refused(sandbox, tmp_path):
    # Before, a misspelt relation type matched nothing: an empty answer (and may_relate
    # said false), where a commit refuses the same name.
    server = start_server(sandbox, wm_binary(), tmp_path / "data")
    probe = sandbox.start("probe", [sys.executable, "-c", UNKNOWN_RELATION_PROBE])
    assert sandbox.wait(probe, 60) == 0, probe.stderr()[-2000:] + server.stderr()[-2000:]
    r = last_json(probe.stdout())
    assert len(r["contain"]["ids"]) == 3 and r["any"] == r["contain"], r  # the three cubes, on the table
    assert "unknown relation type 'skiros:contian' in query" in r["misspelt"].get("refused", ""), r
    assert r["may"] == {"b": True}, r
    assert "unknown relation type 'skiros:contian'" in r["may_misspelt"].get("refused", ""), r
