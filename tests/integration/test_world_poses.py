"""The world model and the physics agree about where the objects are, after every Place
of ClearTable (not only after its final Locate): a containment change (grasp, release)
re-expresses the object's pose in its new container, and Place observes where the
released object landed. The whole system in lockstep, every part a real process; an
observer inside the sandbox (this file, run as a script) compares each product's world
pose in the world model with the physics server's pose whenever a Place node succeeds.
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

from skillbus.skill import State

TOLERANCE_M = 0.01


def _dist(a, b) -> float:
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def connect_world_model(bus, name: str, timeout: float = 60.0):
    """A world-model client, once the server answers."""
    from skillbus.rpc import RpcError
    from skillbus.waiting import wait_until
    from skillbus.world import WorldModelInterface
    from skillbus.world.client import WorldModelError
    return wait_until(lambda: WorldModelInterface(bus, name, timeout=1.0), timeout, f"the world model server ({name})",
                      interval=0.1, step=bus.handle, retry_on=(RpcError, WorldModelError))


def compare(wmi, physics: dict[str, list[float]]) -> dict:
    """Every product's world pose in the world model against the physics server's (by
    label): where the world model has it, its container, and the distance."""
    from skillbus.world.poses import parent_of, world_pose
    out = {}
    for e in wmi.get_elements():
        if e.type not in ("skiros:Cube", "skiros:Product") or e.label not in physics:
            continue
        p, _ = world_pose(wmi, e.id)
        out[e.label] = {"in": parent_of(wmi, e.id), "world_model": [round(x, 4) for x in p],
                        "physics": [round(x, 4) for x in physics[e.label][:3]],
                        "error_m": _dist(p, physics[e.label][:3])}
    return out


def observe_clear_table(timeout: float = 400.0) -> dict:
    """Watches a ClearTable run: at every Place that succeeds and at the end of the
    task, the world model against the physics (the physics state of the frame the Place
    succeeded in)."""
    from skillbus.bus import channel, open_bus
    from skillbus.msgs import decode, sim_state_t, skill_progress_t
    from skillbus.waiting import poll_until
    bus = open_bus()
    physics: dict[int, dict[str, list[float]]] = {}  # frame -> object poses
    progress: list = []
    bus.subscribe(channel("SB_SIM_STATE"), lambda ch, d: _on_state(physics, d))
    bus.subscribe(channel("SB_SKILL_PROGRESS"), lambda ch, d: progress.append(decode(skill_progress_t, d)))
    moves: list = []  # world-model changes that put an object into a container
    bus.subscribe(channel("SB_WM_CHANGES"), lambda ch, d: _on_change(moves, d))
    wmi = connect_world_model(bus, "pose-observer")
    checks: list[dict] = []
    placed: set[int] = set()
    started: dict[str, list[int]] = {"Grasp": [], "Release": []}  # frames the gripper skills started in
    seen_running: set[int] = set()
    final = None

    def take_progress():
        nonlocal final
        while progress:
            p = progress.pop(0)
            if p is None:
                continue
            for n in p.nodes:
                if n.type in started and n.state == State.Running and n.id not in seen_running:
                    seen_running.add(n.id)
                    started[n.type].append(p.header.frame)
            done = [n for n in p.nodes if n.type == "Place" and n.state == State.Success and n.id not in placed]
            if p.state in (State.Success, State.Failure):
                final = p
            if not done and final is None:
                continue
            placed.update(n.id for n in done)
            # Let the world model's changes of this frame reach this replica (they went out
            # before the progress, on another channel), then compare with the physics of
            # the frame the Place ended in (the placed objects lie still by then).
            settle = time.monotonic() + 0.3
            while time.monotonic() < settle:
                bus.handle(0.02)
            frame = p.header.frame
            at = physics.get(frame) or physics[max(physics)]
            checks.append({"frame": frame, "after": "Place" if done else "task",
                           "objects": compare(wmi, at)})
        return final

    poll_until(take_progress, timeout, step=bus.handle)
    return {"checks": checks, "moves": _check_moves(wmi, moves, started, physics), "final": None if final is None else
            {"state": int(final.state), "message": final.nodes[0].message if final.nodes else ""}}


def _on_change(moves: list, data: bytes) -> None:
    """Keeps the changes that make an element contain a product: the grasp and the release."""
    from skillbus.msgs import decode, wm_change_t, wm_op_t
    c = decode(wm_change_t, data)
    if c is None:
        return
    for o in c.ops:
        if o.kind == wm_op_t.ADD_RELATION and o.relation.predicate == "skiros:contain" and \
                o.relation.object.startswith("skiros:Cube"):
            moves.append(c)
            return


def _check_moves(wmi, moves: list, started: dict, physics: dict) -> list[dict]:
    """For each grasp and release transaction: the object's world pose it implies (its
    new local pose composed with its new container's world pose, as the same transaction
    or the world model has it) against the physics pose of the object when that Grasp or
    Release started (held still in the fingers, or lying still on the table)."""
    from skillbus.msgs import wm_op_t
    from skillbus.world.convert import element_from_msg
    from skillbus.quat import rotate
    from skillbus.world.poses import local_pose, world_pose
    out = []
    counts = {"Grasp": 0, "Release": 0}
    for c in moves:
        add = next(o for o in c.ops if o.kind == wm_op_t.ADD_RELATION and o.relation.predicate == "skiros:contain")
        parent, oid = add.relation.subject, add.relation.object
        updated = {o.element.id: element_from_msg(o.element) for o in c.ops if o.kind == wm_op_t.UPDATE_ELEMENT}
        if oid not in updated:
            out.append({"frame": c.header.frame, "object": oid, "error": "no pose written with the containment"})
            continue
        # the new parent's pose: written by this transaction (the gripper: nobody contains it)
        parent_pose = local_pose(updated[parent]) if parent in updated else world_pose(wmi, parent)
        r = rotate(parent_pose[1], local_pose(updated[oid])[0])
        p = tuple(a + b for a, b in zip(parent_pose[0], r))
        kind = "Grasp" if parent.startswith("skiros:Gripper") else "Release"
        k = counts[kind]
        counts[kind] += 1
        label = updated[oid].label
        frame = started[kind][k] if k < len(started[kind]) else None
        at = physics.get(frame, {}).get(label) if frame is not None else None
        out.append({"kind": kind, "object": label, "frame": c.header.frame, "started": frame,
                    "world_model": [round(x, 4) for x in p], "physics": at and [round(x, 4) for x in at[:3]],
                    "error_m": None if at is None else _dist(p, at[:3])})
    return out


def _on_state(physics: dict, data: bytes) -> None:
    from skillbus.msgs import decode, sim_state_t
    s = decode(sim_state_t, data)
    if s is None:
        return
    physics[s.header.frame] = {o.name: list(o.pose) for o in s.objects}
    for f in [f for f in physics if f < s.header.frame - 100_000]:  # a run is a few thousand frames
        del physics[f]


def test_after_every_place_the_world_model_has_each_object_where_the_physics_has_it(tmp_path):
    from conftest import last_json
    from skillbus.netns import Sandbox
    from skillbus.system import programs, start
    run = tmp_path / "run"
    run.mkdir()
    with Sandbox(log_dir=run / "logs") as box:
        observer = box.start("observer", [sys.executable, __file__, "clear_table"])
        procs = start(box, programs(run), run)
        assert box.wait(procs["sim"], 600) == 0, procs["sim"].stderr()[-3000:]
        assert box.wait(observer, 60) == 0, observer.stdout()[-3000:] + observer.stderr()[-3000:]
        r = last_json(observer.stdout())
    print(json.dumps(r, indent=1))
    assert r["final"] and r["final"]["state"] == 3, r["final"]
    places = [c for c in r["checks"] if c["after"] == "Place"]
    assert len(places) == 3, r
    for c in r["checks"]:
        assert sorted(c["objects"]) == ["blue", "green", "red"], c
        for name, o in c["objects"].items():
            if o["in"] == "skiros:Gripper-7":
                continue  # held: where it is, is the arm's business until it is released
            assert o["error_m"] < TOLERANCE_M, (c["frame"], c["after"], name, o)
    # the grasp and the release wrote the object's pose with its new container: where it
    # lay when grasped, where the tool held it when released
    assert [(m.get("kind"), m.get("object")) for m in r["moves"]] == \
        [(k, o) for o in ("red", "green", "blue") for k in ("Grasp", "Release")], r["moves"]
    for m in r["moves"]:
        assert m["error_m"] is not None and m["error_m"] < TOLERANCE_M, m
    # each placed object was in the bin when its Place ended
    for k, c in enumerate(places):
        assert sum(o["in"] == "skiros:Bin-5" for o in c["objects"].values()) == k + 1, c


def reparenting() -> dict:
    """skillbus.world.poses.reparent against a live world model: the demo scene with the
    bin turned a quarter turn, so that the pose in the new container differs in position
    and orientation."""
    import math as m
    from skillbus.bus import open_bus
    from skillbus.world.poses import local_pose, parent_of, reparent, set_world_pose, world_pose
    wmi = connect_world_model(open_bus(), "reparent-test")
    yaw = (0.0, 0.0, m.sin(m.pi / 4), m.cos(m.pi / 4))
    set_world_pose(wmi, "skiros:Bin-5", (0.0, 0.6, 0.0), yaw)
    out = {}
    before = world_pose(wmi, "skiros:Cube-2")
    v0 = wmi.version
    reparent(wmi, "skiros:Cube-2", "skiros:Bin-5")  # it stays where it is
    out["kept"] = {"versions": wmi.version - v0, "in": parent_of(wmi, "skiros:Cube-2"),
                   "containers": len(wmi.get_relations("", "skiros:contain", "skiros:Cube-2")),
                   "before": before, "after": world_pose(wmi, "skiros:Cube-2"),
                   "local": local_pose(wmi.get_element("skiros:Cube-2"))}
    target = ((0.01, 0.62, 0.05), (0.0, 0.0, m.sin(0.1), m.cos(0.1)))
    v0 = wmi.version
    reparent(wmi, "skiros:Cube-2", "skiros:Table-1", target)  # put there
    out["given"] = {"versions": wmi.version - v0, "in": parent_of(wmi, "skiros:Cube-2"),
                    "containers": len(wmi.get_relations("", "skiros:contain", "skiros:Cube-2")),
                    "target": target, "after": world_pose(wmi, "skiros:Cube-2")}
    return out


def test_reparent_writes_the_containment_and_the_pose_in_the_new_container_in_one_transaction(sandbox, tmp_path):
    from conftest import last_json
    from skillbus import paths
    sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", tmp_path / "wm",
                         "--scene", paths.demo_scene().with_suffix("").with_suffix(".ttl")])
    sc = sandbox.start("scenario", [sys.executable, __file__, "reparent"])
    assert sandbox.wait(sc, 120) == 0, sc.stdout()[-3000:] + sc.stderr()[-3000:]
    r = last_json(sc.stdout())
    print(json.dumps(r))
    kept, given = r["kept"], r["given"]
    assert kept["versions"] == 1 and kept["in"] == "skiros:Bin-5" and kept["containers"] == 1, kept
    for a, b in zip(kept["before"][0] + kept["before"][1], kept["after"][0] + kept["after"][1]):
        assert abs(a - b) < 1e-5, kept
    # table-relative (-0.1, 0.15, 0.425) is world (0.4, 0.15, 0.425); in the turned bin at (0, 0.6, 0):
    # d = (0.4, -0.45, 0.425) turned back a quarter: (-0.45, -0.4, 0.425)
    assert [round(x, 4) for x in kept["local"][0]] == [-0.45, -0.4, 0.425], kept
    assert given["versions"] == 1 and given["in"] == "skiros:Table-1" and given["containers"] == 1, given
    for a, b in zip(given["target"][0] + given["target"][1], given["after"][0] + given["after"][1]):
        assert abs(a - b) < 1e-5, given


if __name__ == "__main__":
    if sys.argv[1] == "clear_table":
        print(json.dumps(observe_clear_table()), flush=True)
    elif sys.argv[1] == "reparent":
        print(json.dumps(reparenting()), flush=True)
