"""What the processes that hear the physics' state cost the physics, without doing anything.

The demo's physics server publishes its state at the start of every frame, and every
participant on the other core is woken by it. This runs the physics alone on the demo's
recorded commands (as bench/pick_and_place.py does, placed the same way), interleaved:
with nobody listening, and with SUBSCRIBERS processes on the participants' cores that
subscribe to the state and the arm state and only read them. It prints each run's real-time
factor and the physics server's own split of a frame (publishing the state, the step).

Not in `make bench` (a question asked once, docs/benchmarks.md "Pick and place"):

    deploy/netns-run .venv/bin/python bench/state_fanout.py [--repeats N]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
from pathlib import Path

from pick_and_place import alone, demo
from skillbus import cpu_layout
from skillbus.netns import Sandbox

SUBSCRIBERS = 5  # the demo's processes that hear the state: skills, gripper, manager, world model, motion

LISTENER = r'''
from skillbus.bus import open_bus
from skillbus.robot.messages import arm_state_channel
from skillbus.sim.messages import state_channel
bus = open_bus()
for ch in (state_channel(), arm_state_channel()):
    bus.subscribe(ch, lambda c, d: None)
print("listening", flush=True)
while True:
    bus.handle(1.0)
'''


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=6, help="pairs of runs (default 6)")
    args = ap.parse_args()
    figures: dict[str, list[dict]] = {"nobody listening": [], f"{SUBSCRIBERS} listeners": []}
    with tempfile.TemporaryDirectory() as tmp:
        run = Path(tmp) / "run"
        run.mkdir()
        with Sandbox(log_dir=run / "logs") as box:
            d = demo(box, run, 20.0)
            allowed = os.sched_getaffinity(0)  # (the demo's placement: the physics on the last core)
            others = cpu_layout.cpu_list(allowed - {max(allowed)} or allowed)
            for rep in range(args.repeats):
                for kind in (list(figures) if rep % 2 == 0 else list(figures)[::-1]):
                    listeners = []
                    if kind != "nobody listening":
                        listeners = [box.start(f"listener-{rep}-{i}", ["taskset", "--cpu-list", others, sys.executable,
                                                                      "-c", LISTENER]) for i in range(SUBSCRIBERS)]
                        for p in listeners:  # (subscribed before the run)
                            p.wait_for("listening", 30, stream="stdout")
                    a = alone(box, d["script"], d["frames"], 20.0, d["physics_prefix"], d["physics_options"])
                    for p in listeners:
                        box.kill(p)
                    split = a.get("frame_ms", {})
                    figures[kind].append({"rtf": a["real_time_factor"], **split})
                    print(f"{kind:18s} {a['real_time_factor']:6.2f}x real time; per frame (ms): state "
                          f"{split.get('state', 0):.3f}, physics {split.get('physics', 0):.3f}", flush=True)
    for kind, runs in figures.items():
        print(f"{kind:18s} median {statistics.median(r['rtf'] for r in runs):6.2f}x; state "
              f"{statistics.median(r.get('state', 0) for r in runs):.3f} ms, physics "
              f"{statistics.median(r.get('physics', 0) for r in runs):.3f} ms a frame")
    return 0


if __name__ == "__main__":
    sys.exit(main())
