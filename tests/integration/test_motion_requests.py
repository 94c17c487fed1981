"""The motion service off the happy path, over the bus: a held box of impossible size is
refused naming it; with --map and no map server, a straight line (which never asks the
map) is still planned; a line never leaves the next joint-space move without the map."""

from __future__ import annotations

import json
import sys

from skillbus import paths

PROBE = r'''
import json, sys
from skillbus.bus import open_bus
from skillbus.msgs import motion_plan_t, motion_request_t
from skillbus.rpc import RpcClient, RpcError
rpc = RpcClient(open_bus(None), "MOTION", "probe")
def ask(held, cartesian, target):
    r = motion_request_t()
    r.joint_names = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6"]; r.num_joints = 6
    r.start = [0.0, 0.2, 1.6, 0.0, 1.3416, 0.0]
    r.target = target; r.cartesian = cartesian; r.step_m = 0.01; r.speed_scale = 0.5
    r.held = held; r.as_of_frame = -1
    try:
        p = rpc.call("plan", r, motion_plan_t, timeout=5.0)
        return {"ok": p.ok, "how": p.how, "error": p.error}
    except RpcError as e:
        return {"refused": str(e)}
down = [0.4006, 0.0, 0.55, 0.0, 1.0, 0.0, 0.0]
print(json.dumps({"huge": ask([3.0, 0.05, 0.05], True, down), "negative": ask([-0.05, 0.05, 0.05], True, down),
                  "line": ask([0.05, 0.05, 0.05], True, down)}))
'''


def test_bad_held_boxes_are_refused_and_lines_need_no_map(sandbox):
    motion = sandbox.start("motion", [str(paths.binary("motion_server")), "--scene", str(paths.demo_scene()), "--map"])
    motion.wait_for("serving", 30)
    p = sandbox.start("probe", [sys.executable, "-c", PROBE])
    assert sandbox.wait(p, 60) == 0, p.stderr()
    r = json.loads(p.stdout().strip().splitlines()[-1])
    for case in ("huge", "negative"):
        assert "a held object's sides must be within [0, 2] m" in r[case].get("refused", ""), r
    assert r["line"] == {"ok": True, "how": "line", "error": ""}, r  # no map server: a line does not ask it


MAP_PROBE = r'''
import json, sys
from skillbus.bus import open_bus
from skillbus.msgs import motion_plan_t, motion_request_t
from skillbus.rpc import RpcClient, RpcError
rpc = RpcClient(open_bus(None), "MOTION", "probe")
def ask(cartesian, start, target):
    r = motion_request_t()
    r.joint_names = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6"]; r.num_joints = 6
    r.start = start
    r.target = target; r.cartesian = cartesian; r.step_m = 0.01; r.speed_scale = 0.5
    r.held = [0.0, 0.0, 0.0]; r.as_of_frame = -1
    p = rpc.call("plan", r, motion_plan_t, timeout=30.0)
    return p
home = [0.0, 0.2, 1.6, 0.0, 1.3416, 0.0]
first = ask(False, home, [0.45, 0.0, 0.6, 0.0, 1.0, 0.0, 0.0])  # a joint-space move: the map goes in
assert first.ok, first.error
low = ask(True, home, [0.4, 0.0, 0.43, 0.0, 1.0, 0.0, 0.0])  # a line down beside the red cube
assert low.ok, low.error
across = ask(False, list(low.goal), [0.4, 0.3, 0.43, 0.0, 1.0, 0.0, 0.0])  # low across where the red cube is
print(json.dumps({"low": low.how, "across": {"ok": across.ok, "how": across.how, "error": across.error}}))
'''


def test_a_straight_line_leaves_the_map_in_the_next_joint_moves_check(sandbox, tmp_path):
    # A line is checked without the map (it goes the last centimetres to what the map holds
    # as occupied), so the line took the map out of the collision model; the map's cache
    # still held it, so the next joint-space move (the map unchanged) was planned against
    # the fixtures alone: straight through the red cube, which only the map holds.
    from test_occupancy_map import mapped_overhead
    maps = tmp_path / "maps"
    maps.mkdir()
    mapped_overhead(sandbox, tmp_path, maps)
    motion = sandbox.start("motion", [str(paths.binary("motion_server")), "--scene", str(paths.demo_scene()), "--map"])
    motion.wait_for("serving", 30)
    p = sandbox.start("probe", [sys.executable, "-c", MAP_PROBE])
    assert sandbox.wait(p, 120) == 0, p.stderr()
    r = json.loads(p.stdout().strip().splitlines()[-1])
    assert r["low"] == "line" and r["across"]["how"] != "direct", r


SPEED_PROBE = r'''
import json, math
from skillbus.bus import open_bus
from skillbus.msgs import motion_plan_t, motion_request_t
from skillbus.rpc import RpcClient, RpcError
rpc = RpcClient(open_bus(None), "MOTION", "probe")
def ask(speed_scale, step_m=0.01):
    r = motion_request_t()
    r.joint_names = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6"]; r.num_joints = 6
    r.start = [0.0, 0.2, 1.6, 0.0, 1.3416, 0.0]
    r.target = [0.45, 0.0, 0.6, 0.0, 1.0, 0.0, 0.0]; r.cartesian = False; r.step_m = step_m
    r.speed_scale = speed_scale; r.held = [0.0, 0.0, 0.0]; r.as_of_frame = -1
    try:
        p = rpc.call("plan", r, motion_plan_t, timeout=10.0)
        return {"ok": p.ok, "end_s": p.points[-1].time_from_start_ns * 1e-9 if p.points else None}
    except RpcError as e:
        return {"refused": str(e)}
print(json.dumps({"tiny": ask(1e-12), "tinier": ask(1e-11), "over": ask(2.0), "nan": ask(math.nan),
                  "default": ask(0.0), "slow": ask(0.05), "step_inf": ask(0.5, math.inf)}))
'''


def test_a_speed_scale_out_of_range_is_refused_not_turned_into_another_speed(sandbox):
    # Before, 1e-12 overflowed a segment's time into the shortest one: the fastest move,
    # answered ok; 2.0 was taken as 1 without a word.
    motion = sandbox.start("motion", [str(paths.binary("motion_server")), "--scene", str(paths.demo_scene())])
    motion.wait_for("serving", 30)
    p = sandbox.start("probe", [sys.executable, "-c", SPEED_PROBE])
    assert sandbox.wait(p, 60) == 0, p.stderr()
    r = json.loads(p.stdout().strip().splitlines()[-1])
    for case in ("tiny", "tinier", "over", "nan"):
        assert "speed_scale" in r[case].get("refused", "") and "must be within [0.01" in r[case]["refused"], r
    assert "step_m" in r["step_inf"].get("refused", ""), r
    assert r["default"]["ok"] and r["slow"]["ok"] and r["slow"]["end_s"] > 5 * r["default"]["end_s"], r
