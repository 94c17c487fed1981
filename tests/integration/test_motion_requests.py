"""The motion service off the happy path, over the bus: a held box of impossible size is
refused naming it; with --map and no map server, a straight line (which never asks the
map) is still planned."""

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
