"""Benchmarks of the skill manager, each beside its peers measured in the same run.

(a) Tick overhead of a 1,000-node tree of trivial always-succeeding C++ leaves under a
    Serial node (our tree engine, bench/tree_tick_bench.cpp), beside BehaviorTree.CPP
    (the behaviortreepy wheel: a Sequence of 1,000 AlwaysSuccess from XML, one Python
    call per tick) and py_trees (a Sequence without memory of 1,000 Success behaviours).
    Targets: no slower than BehaviorTree.CPP, at least 50x faster than py_trees.
(b) The round trip of one Python primitive tick through the manager's code
    (bench/tick_rtt_bench.cpp: a RemotePrimitive ticking a skill process over LCM),
    beside a raw Python LCM round trip (bench/pingpong.py). Target: within 2x.

Run: .venv/bin/python bench/skill_ticks.py   (in `make bench`)
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

from skillbus import paths
from skillbus.netns import Sandbox, last_json

HERE = Path(__file__).resolve().parent
LEAVES, TICKS = 1000, 2000


def ours() -> float:
    out = subprocess.run([paths.build_dir() / "bench" / "tree_tick_bench", str(LEAVES), str(TICKS)],
                         capture_output=True, text=True, check=True).stdout
    return json.loads(out)["us_per_tick"]


def behaviortree_cpp() -> float:
    import behaviortreepy as bt
    xml = ('<root BTCPP_format="4"><BehaviorTree ID="Main"><Sequence>' + "<AlwaysSuccess/>" * LEAVES +
           "</Sequence></BehaviorTree></root>")
    tree = bt.BehaviorTreeFactory().create_tree_from_text(xml)
    for _ in range(100):
        tree.tick_once()
    t0 = time.perf_counter()
    for _ in range(TICKS):
        tree.tick_once()
    return (time.perf_counter() - t0) / TICKS * 1e6


def py_trees_figure() -> float:
    import py_trees
    root = py_trees.composites.Sequence("root", memory=False,
                                        children=[py_trees.behaviours.Success(f"s{i}") for i in range(LEAVES)])
    tree = py_trees.trees.BehaviourTree(root)
    for _ in range(10):
        tree.tick()
    n = 200
    t0 = time.perf_counter()
    for _ in range(n):
        tree.tick()
    return (time.perf_counter() - t0) / n * 1e6


def tick_round_trip(ticks: int) -> tuple[dict, dict]:
    with Sandbox() as box:
        pong = box.start("pong", [sys.executable, HERE / "pingpong.py", "pong"])
        ping = box.start("ping", [sys.executable, HERE / "pingpong.py", "ping", str(ticks), "200"])
        box.wait(ping, 120)
        box.kill(pong)
        raw = last_json(ping.stdout())
        # A real manager to register with (the process serves its ticks as in a real system;
        # the bench's tick_rtt_bench plays the manager's node that ticks it).
        box.start("skill_mgr", [paths.build_dir() / "skill_mgr" / "skill_mgr", "--wall-clock"])
        proc = box.start("skills", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "bench",
                                    "--library", "spin_skills", "--register-timeout", "60"], env={"PYTHONPATH": str(HERE)})
        try:
            proc.wait_for("registered", 60)
        except RuntimeError as e:
            raise SystemExit(f"the skill process did not register: {e}")
        rtt = box.start("rtt", [paths.build_dir() / "bench" / "tick_rtt_bench", "SKPROC_BENCH", "spin", str(ticks)])
        box.wait(rtt, 120)
        got = last_json(rtt.stdout())
        if got is None or "error" in got:
            raise SystemExit(f"tick_rtt_bench failed: {rtt.stdout()} {rtt.stderr()[-2000:]}")
        return raw, got


def main() -> int:
    a = statistics.median(ours() for _ in range(3))
    b = statistics.median(behaviortree_cpp() for _ in range(3))
    c = py_trees_figure()
    print(f"(a) tick of a {LEAVES}-leaf tree (Serial/Sequence of always-succeeding leaves), us per tick")
    print(f"    skillbus tree engine   {a:10.1f}")
    print(f"    BehaviorTree.CPP       {b:10.1f}   ratio BT.CPP/ours  {b / a:6.2f}  (target >= 1)")
    print(f"    py_trees               {c:10.1f}   ratio py_trees/ours {c / a:6.1f}  (target >= 50)")
    raw, rtt = tick_round_trip(2000)
    print("(b) one Python primitive tick through the manager, us (median / p99)")
    print(f"    manager -> skill process -> manager  {rtt['median_us']:8.1f} / {rtt['p99_us']:8.1f}")
    print(f"    raw Python LCM round trip (200 B)    {raw['median_us']:8.1f} / {raw['p99_us']:8.1f}")
    print(f"    ratio {rtt['median_us'] / raw['median_us']:.2f}  (target <= 2)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
