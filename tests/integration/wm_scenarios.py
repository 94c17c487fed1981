"""World-model scenarios that run inside the test sandbox, next to a running wm_server.
Each asserts what it checks and exits non-zero with the failing line when a check fails.
Usage: wm_scenarios.py api | bad_input | scene_files | writer N | lockstep_writer FRAMES"""

from __future__ import annotations

import json
import random
import sys
from pathlib import Path

from skillbus.bus import channel, open_bus
from skillbus.msgs import rpc_reply_t, wm_change_t, wm_elements_t, wm_op_t
from skillbus.rpc import RpcClient, RpcRemoteError
from skillbus.world import Element, WorldModelError, WorldModelInterface
from skillbus.world.client import _query
from skillbus.world.convert import op


def expect_error(fn, needle: str) -> str:
    try:
        fn()
    except WorldModelError as e:
        assert needle in str(e), f"expected {needle!r} in {e}"
        return str(e)
    raise AssertionError(f"expected an error with {needle!r}")


def api() -> None:
    wmi = WorldModelInterface(open_bus(), "api-test")
    v0 = wmi.version
    # get and query (subclasses)
    assert wmi.get_element("skiros:Cube-2").label == "red"
    assert [e.id for e in wmi.resolve_elements(Element("skiros:Product"))] == \
        ["skiros:Cube-2", "skiros:Cube-3", "skiros:Cube-4"]
    assert [e.id for e in wmi.resolve_elements(Element("skiros:Location"))] == \
        ["skiros:Bin-5", "skiros:Scene-0", "skiros:Table-1"]
    assert [e.label for e in wmi.resolve_elements(Element("skiros:Cube", "green"))] == ["green"]
    on_table = Element("skiros:Cube")
    on_table.addRelation("skiros:Table-1", "skiros:contain", "-1")
    assert len(wmi.resolve_elements(on_table)) == 3
    # add with relations; the server gives the id
    new = Element("skiros:Cylinder", "can")
    new.setProperty("skiros:PositionX", 0.2)
    new.addRelation("skiros:Table-1", "skiros:contain", "-1")
    new = wmi.add_element(new)
    assert new.id == "skiros:Cylinder-10", new.id  # after the demo's nine (the post is skiros:Obstacle-9)
    assert wmi.get_relations("skiros:Table-1", "skiros:contain", new.id)
    # update properties and relations
    new.setProperty("skiros:PositionX", 0.3)
    new.setRelation("skiros:Bin-5", "skiros:contain", "-1")
    new.removeRelations(new.getRelations(subj="skiros:Table-1"))
    wmi.update_element(new)
    assert wmi.get_element(new.id).getProperty("skiros:PositionX").value == 0.3
    assert wmi.get_relations(subj="skiros:Bin-5", obj=new.id) and not wmi.get_relations("skiros:Table-1", "", new.id)
    # set_relation both ways; into a container it moves the element (containment is a tree)
    wmi.set_relation("skiros:Gripper-7", "skiros:contain", "skiros:Cube-2")
    assert wmi.get_element("skiros:Cube-2").hasRelation("skiros:Gripper-7", "skiros:contain", "-1")
    assert not wmi.get_relations("skiros:Table-1", "skiros:contain", "skiros:Cube-2")
    wmi.set_relation("skiros:Table-1", "skiros:contain", "skiros:Cube-2")  # back onto the table
    assert not wmi.get_relations("skiros:Gripper-7", "skiros:contain", "skiros:Cube-2")
    wmi.set_relation("skiros:Gripper-7", "skiros:contain", "skiros:Cube-2", False)  # (nothing to remove)
    assert wmi.get_relations("skiros:Table-1", "skiros:contain", "skiros:Cube-2")
    # transactions: all or nothing, and version conflicts
    before = (wmi.version, [e.printState(True) for e in wmi.get_elements()])
    expect_error(lambda: wmi.commit([op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube", "ok")),
                                     op(wm_op_t.ADD_RELATION, relation=("skiros:Table-1", "skiros:contain",
                                                                        "skiros:Ghost-1"))]),
                 "operation 2: relation (skiros:Table-1 skiros:contain skiros:Ghost-1): no element skiros:Ghost-1")
    wmi.sync()
    assert (wmi.version, [e.printState(True) for e in wmi.get_elements()]) == before
    expect_error(lambda: wmi.commit([op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube"))], wmi.version - 1),
                 "version conflict")
    wmi.commit([op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube", "expected"))], wmi.version)
    # remove takes relations along
    wmi.remove_element(new)
    assert not wmi.get_relations(obj=new.id)
    expect_error(lambda: wmi.get_element(new.id), "no element")
    # transforms through the tree: Scene-0 > Table-1 (x 0.5) > Cube-2 (-0.1, 0.15, 0.425)
    t, q = wmi.get_transform("skiros:Cube-2", "map")
    assert [round(x, 9) for x in t] == [0.4, 0.15, 0.425] and q == [0.0, 0.0, 0.0, 1.0], (t, q)
    t, _ = wmi.get_transform("skiros:Cube-2", "skiros:Cube-3")
    assert [round(x, 9) for x in t] == [-0.1, 0.25, 0.0], t
    # abstract relations
    assert wmi.may_relate("skiros:Table", "skiros:contain", "skiros:Cube")
    assert not wmi.may_relate("skiros:Cube", "skiros:contain", "skiros:Table")
    # save, change, load: back to the saved world
    saved = wmi.save_scene()
    snapshot = [e.printState(True) for e in wmi.get_elements()]
    wmi.remove_element("skiros:Cube-3")
    wmi.load_scene(turtle=saved)
    assert [e.printState(True) for e in wmi.get_elements()] == snapshot
    assert wmi.version > v0
    # a replica that sees a gap in versions resyncs before its next read
    other = WorldModelInterface(open_bus(), "other-writer")
    other.add_element(Element("skiros:Cube", "behind-your-back"))
    gap = wm_change_t()
    gap.version = wmi.version + 5  # as if changes had been lost
    wmi._on_change(gap.encode())
    assert wmi._stale
    assert any(e.label == "behind-your-back" for e in wmi.get_elements())
    assert wmi.version == other.version
    print(json.dumps({"ok": True, "version": wmi.version}))


def bad_input() -> None:
    wmi = WorldModelInterface(open_bus(), "bad-input-test")
    before = (wmi.version, [e.printState(True) for e in wmi.get_elements()])
    expect_error(lambda: wmi.get_element("skiros:Nope-1"), "no element skiros:Nope-1")
    expect_error(lambda: wmi._call("get", _query(ids=["skiros:Nope-1"]), wm_elements_t),
                 "unknown element id 'skiros:Nope-1'")
    bad = Element("skiros:Cube", "bad")
    bad.setProperty("skiros:PositionX", "left")
    expect_error(lambda: wmi.add_element(bad), "skiros:PositionX of skiros:Cube-")
    expect_error(lambda: wmi.add_element(Element("skiros:Unicorn")), "unknown type 'skiros:Unicorn'")
    # A NaN or infinite number never reaches the world (sent as raw transactions: the
    # server must refuse them whatever a client lets through).
    from skillbus.msgs import header_t, wm_commit_t, wm_txn_t
    from skillbus.world.convert import element_msg, op as op_of
    for x in (float("nan"), float("inf"), float("-inf")):
        e = Element("skiros:Cube", "nan")
        e.setProperty("skiros:PositionX", 0.0)
        m = element_msg(e)
        m.properties[[q.key for q in m.properties].index("skiros:PositionX")].values[0].f = x
        o = op_of(wm_op_t.ADD_ELEMENT)
        o.element = m
        txn = wm_txn_t()
        txn.header, txn.client_id, txn.request_id, txn.expected_version = header_t(), "nan-test", 1, -1
        txn.ops, txn.num_ops = [o], 1
        try:
            RpcClient(open_bus(), "WM", f"nan-{x}").call("commit", txn, wm_commit_t, timeout=2.0)
            raise AssertionError(f"a commit with PositionX={x} was accepted")
        except RpcRemoteError as err:
            assert "is not a finite number" in str(err), err
    expect_error(lambda: wmi.set_relation("skiros:Table-1", "skiros:contain", "skiros:Ghost-3"),
                 "no element skiros:Ghost-3")
    expect_error(lambda: wmi.set_relation("skiros:Table-1", "skiros:likes", "skiros:Cube-2"),
                 "unknown relation type skiros:likes")
    expect_error(lambda: wmi.load_scene(turtle="@prefix x: <http://x#> .\nx:a x:b \"unterminated .\n"),
                 "malformed Turtle")
    expect_error(lambda: wmi.get_transform("skiros:Cube-2", "nowhere"), "unknown frame 'nowhere'")
    # a truncated and a garbage request: no reply can be matched, the server must live on
    bus = open_bus()
    raw = RpcClient(bus, "WM", "raw")
    for payload in (b"\x00\x01", b"garbage" * 10):
        try:
            raw.call_raw("commit", payload, timeout=1.0)
            raise AssertionError("a garbage commit was accepted")
        except RpcRemoteError as e:
            assert e.status == rpc_reply_t.BAD_REQUEST and "does not decode" in str(e), e
    for junk in (b"", b"\xff" * 40, b"\x12\x34" * 300):
        bus.publish(channel("SB_WM_REQ"), junk)
        bus.publish(channel("SB_WM_TXN"), junk)
    wmi.sync()
    assert (wmi.version, [e.printState(True) for e in wmi.get_elements()]) == before
    print(json.dumps({"ok": True}))


def saved_scene_then_a_commit(wmi: WorldModelInterface):
    """Saves the world as DATA/scenes/saved.ttl, then commits 'before-load'; the request
    that names the saved scene (to load it again), and the version after the commit."""
    from skillbus.msgs import wm_scene_t
    req = wm_scene_t()
    req.path = "saved"
    wmi._call("save_scene", req, wm_scene_t)
    wmi.commit([op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube", "before-load"))])
    return req, wmi.version


def failed_load(data: str) -> None:
    """A scene load that cannot be made durable (its snapshot cannot be written) changes
    nothing: the world and its version are as before, and later commits are kept."""
    from skillbus.msgs import wm_scene_t
    wmi = WorldModelInterface(open_bus(), "failed-load")
    req, version = saved_scene_then_a_commit(wmi)
    blocker = Path(data) / "snapshot.bin.tmp"
    blocker.mkdir()
    req.path = "saved.ttl"
    err = expect_error(lambda: wmi._call("load_scene", req, wm_scene_t), "could not be made durable, nothing changed")
    blocker.rmdir()
    wmi.commit([op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube", "after-load"))])
    labels = sorted(e.label for e in wmi.get_elements() if e.label.endswith("-load"))
    print(json.dumps({"ok": True, "error": err, "version_before": version, "version": wmi.version,
                      "labels": labels}), flush=True)


def journal_switch_fails(data: str) -> None:
    """A scene load whose snapshot is written but whose new journal cannot be started: the
    disk and the server hold the new scene, and no commit is taken until a restart."""
    from skillbus.msgs import wm_scene_t
    wmi = WorldModelInterface(open_bus(), "journal-switch")
    req, version = saved_scene_then_a_commit(wmi)
    (Path(data) / "journal.bin.tmp").mkdir()
    req.path = "saved.ttl"
    err = expect_error(lambda: wmi._call("load_scene", req, wm_scene_t), "is on disk as a snapshot")
    refused = expect_error(lambda: wmi.commit([op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube", "after"))]),
                           "restart the server")
    print(json.dumps({"ok": True, "error": err, "refused": refused, "version_before": version}), flush=True)


def change_blocked(data: str, what: str) -> None:
    """Commits 'before-change', prints the version, then makes a scene change (a load of
    the demo scene with a new class, or the class as a new axiom) whose snapshot blocks
    for ever (snapshot.bin.tmp is a FIFO nobody reads): the test kills the server there."""
    import os
    from skillbus.msgs import wm_scene_t
    wmi = WorldModelInterface(open_bus(), "change-blocked", timeout=2.0)
    wmi.commit([op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube", "before-change"))])
    print(json.dumps({"version_before": wmi.version}), flush=True)
    os.mkfifo(Path(data) / "snapshot.bin.tmp")
    axiom = "skiros:Widget rdfs:subClassOf skiros:Product ."
    req = wm_scene_t()
    if what == "load":
        req.turtle = (Path(__file__).resolve().parents[2] / "deploy" / "scenes" / "demo.ttl").read_text() + axiom + "\n"
        name = "load_scene"
    else:
        req.turtle = axiom
        name = "add_axioms"
    try:
        wmi._call(name, req, wm_scene_t)
    except WorldModelError as e:
        print(json.dumps({"error": str(e)}), flush=True)


def failed_axioms(data: str) -> None:
    """New axioms that cannot be made durable change nothing: no new class, the same
    version, and the next commit is taken."""
    from skillbus.msgs import wm_scene_t
    wmi = WorldModelInterface(open_bus(), "failed-axioms")
    version = wmi.version
    blocker = Path(data) / "snapshot.bin.tmp"
    blocker.mkdir()
    req = wm_scene_t()
    req.turtle = "skiros:Widget rdfs:subClassOf skiros:Product ."
    err = expect_error(lambda: wmi._call("add_axioms", req, wm_scene_t), "could not be made durable, nothing changed")
    blocker.rmdir()
    unchanged = {"version": wmi.version, "widget": "Widget" in wmi.save_scene()}
    wmi.commit([op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube", "after-axioms"))])
    print(json.dumps({"ok": True, "error": err, "version_before": version, "unchanged": unchanged,
                      "version_after_commit": wmi.version}), flush=True)


def writer(n: int) -> None:
    """Adds n elements labelled w0..w{n-1}, one transaction each; prints each acknowledged
    index. Retries ride through a server restart (RPC timeout 20 s)."""
    wmi = WorldModelInterface(open_bus(), "crash-writer", timeout=20.0)
    for i in range(n):
        wmi.commit([op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube", f"w{i}"))])
        print(f"ack {i}", flush=True)
    print(json.dumps({"ok": True, "written": n}), flush=True)


def lockstep_writer(frames: int) -> None:
    """A lockstep participant that writes a scripted sequence of transactions."""
    from skillbus.lockstep import LockstepParticipant
    bus = open_bus()
    p = LockstepParticipant(bus, "writer")
    wmi = WorldModelInterface(bus, "writer", participant=p)
    rng = random.Random(7)  # seeded: the same script every run

    def on_frame(frame: int, t: int) -> None:
        if frame % 3 == 0:
            c = Element("skiros:Cube", f"c{frame}")
            c.setProperty("skiros:PositionX", rng.uniform(-0.2, 0.2))
            wmi.commit_async([op(wm_op_t.ADD_ELEMENT, element=c)])
        cubes = [e for e in wmi.get_elements() if e.type == "skiros:Cube"]
        if cubes and frame % 3 == 1:
            e = cubes[rng.randrange(len(cubes))]
            e.setProperty("skiros:PositionY", rng.uniform(-0.2, 0.2))
            wmi.commit_async([op(wm_op_t.UPDATE_ELEMENT, element=e)])
        if cubes and frame % 5 == 2:
            e = cubes[rng.randrange(len(cubes))]
            wmi.commit_async([op(wm_op_t.ADD_RELATION, relation=("skiros:Table-1", "skiros:contain", e.id))])

    p.on_frame = on_frame
    r = p.run()
    print(json.dumps({"ok": r.ok, "error": r.error, "frames": r.frames, "version": wmi.version,
                      "digest": r.digest_hex, "elements": len(wmi.get_elements())}), flush=True)
    sys.exit(0 if r.ok else 1)


def scene_files(data: str) -> None:
    """Scene files by name only, inside DATA/scenes: a path never reaches the disk. A
    save that cannot be written fails naming why and leaves the saved scene whole."""
    from skillbus.msgs import wm_scene_t
    wmi = WorldModelInterface(open_bus(), "scene-files-test")

    def call(method: str, path: str):
        req = wm_scene_t()
        req.path = path
        return wmi._call(method, req, wm_scene_t)

    for bad in ("../journal.bin", "/etc/passwd", "scenes/../../journal", ".journal", "a/b", ""):
        if bad:
            err = expect_error(lambda: call("save_scene", bad), "a name, not a path")
        err = expect_error(lambda: call("load_scene", bad or "../x"), "a name, not a path")
        assert "root:" not in err, err
    saved = call("save_scene", "snap-1")
    assert saved.path == "snap-1" and "skiros:Cube-2" in saved.turtle
    on_disk = Path(data) / "scenes" / "snap-1.ttl"
    assert on_disk.read_text() == saved.turtle
    # A write that fails (here its file beside cannot be made; a full disk fails alike):
    # refused, naming why, and the file saved before is whole (before, it was truncated
    # first and then written in place).
    blocker = Path(data) / "scenes" / "snap-1.ttl.tmp"
    blocker.mkdir()
    expect_error(lambda: call("save_scene", "snap-1"), "cannot write the scene snap-1")
    assert on_disk.read_text() == saved.turtle
    blocker.rmdir()
    expect_error(lambda: call("load_scene", "no-such-scene"), "cannot read")
    loaded = call("load_scene", "snap-1.ttl")
    print(json.dumps({"ok": True, "loaded_version": loaded.version}), flush=True)


if __name__ == "__main__":
    what = sys.argv[1]
    if what == "api":
        api()
    elif what == "bad_input":
        bad_input()
    elif what == "scene_files":
        scene_files(sys.argv[2])
    elif what == "failed_axioms":
        failed_axioms(sys.argv[2])
    elif what == "change_blocked":
        change_blocked(sys.argv[2], sys.argv[3])
    elif what == "journal_switch_fails":
        journal_switch_fails(sys.argv[2])
    elif what == "failed_load":
        failed_load(sys.argv[2])
    elif what == "writer":
        writer(int(sys.argv[2]))
    elif what == "lockstep_writer":
        lockstep_writer(int(sys.argv[2]))
    else:
        sys.exit(f"unknown scenario {what}")
