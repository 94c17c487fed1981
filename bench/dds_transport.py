"""Benchmark: Cyclone DDS beside LCM, in the same run (issue "Cyclone DDS transport").

1. A Python round trip (publish, echo, receive; 96 bytes, no key) over LCM's own Python
   module, skillbus's bus on udpm://, and skillbus's bus on dds://.
2. Bare lockstep frames (bench/lockstep_overhead.py's session: the C++ clock master and
   1, 2, 4, 8 Python or C++ participants, signed as deployed) on each transport.
3. The pick-and-place demo at 20 ms frames on each transport: its real-time factor, and
   that both give the same digests.

Targets: with 4 Python participants a DDS frame within 1.5x of an LCM frame; with 8,
DDS below LCM (DDS delivers a topic only to its readers). Each figure is the median of
REPEATS interleaved runs; everything runs in private network namespaces.

Run: .venv/bin/python bench/dds_transport.py [--frames N] [--repeats N] [--no-demo]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
from pathlib import Path

from lockstep_overhead import lockstep, raw_round_trip
from skillbus.netns import Sandbox

TRANSPORTS = ("lcm", "dds")
COUNTS = (1, 2, 4, 8)


def demo_rtf(transport: str) -> dict:
    from pick_and_place import demo
    with tempfile.TemporaryDirectory() as tmp:
        run = Path(tmp)
        with Sandbox(log_dir=run / "logs", transport=transport) as box:
            d = demo(box, run, 20.0)
    return {"rtf": d["real_time_factor"], "task": d["task"], "state": d["state_digest"],
            "session": d.get("session_digest")}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=2000)
    ap.add_argument("--round-trips", type=int, default=2000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--no-demo", action="store_true")
    args = ap.parse_args()
    rt: dict[str, list[float]] = {"lcm module": [], "bus udpm://": [], "bus dds://": []}
    frames: dict[tuple[str, str, int], list[float]] = {}
    for _ in range(args.repeats):
        for transport in TRANSPORTS:
            with Sandbox(transport=transport) as box:
                if transport == "lcm":
                    rt["lcm module"].append(raw_round_trip(box, args.round_trips, 96, via="lcm")["median_us"])
                    rt["bus udpm://"].append(raw_round_trip(box, args.round_trips, 96, via="bus")["median_us"])
                else:
                    rt["bus dds://"].append(raw_round_trip(box, args.round_trips, 96, via="bus")["median_us"])
                for lang in ("py", "cpp"):
                    for n in COUNTS:
                        us = lockstep(box, n, lang, args.frames, signed=True)["us_per_frame"]
                        frames.setdefault((transport, lang, n), []).append(us)
    print(f"Cyclone DDS beside LCM, median of {args.repeats} ({platform.machine()}, "
          f"{len(os.sched_getaffinity(0))} cores)")
    print("Python round trip (96 B, no key), median us:")
    for name, v in rt.items():
        print(f"    {name:14s} {statistics.median(v):8.1f}")
    print(f"bare lockstep frames ({args.frames} each, signed), us per frame:")
    print(f"{'participants':>14} {'language':>8} {'LCM':>8} {'DDS':>8} {'DDS / LCM':>10}")
    med = {k: statistics.median(v) for k, v in frames.items()}
    for lang in ("py", "cpp"):
        for n in COUNTS:
            a, b = med[("lcm", lang, n)], med[("dds", lang, n)]
            print(f"{n:>14} {('Python' if lang == 'py' else 'C++'):>8} {a:8.1f} {b:8.1f} {b / a:10.2f}")
    r4 = med[("dds", "py", 4)] / med[("lcm", "py", 4)]
    r8 = med[("dds", "py", 8)] / med[("lcm", "py", 8)]
    print(f"target (4 Python participants: a DDS frame within 1.5x of an LCM frame): "
          f"{'met' if r4 <= 1.5 else 'NOT met'} ({r4:.2f}x)")
    print(f"target (8 Python participants: a DDS frame below an LCM frame): {'met' if r8 < 1 else 'NOT met'} ({r8:.2f}x)")
    if not args.no_demo:
        demos = {t: demo_rtf(t) for t in TRANSPORTS}
        for t, d in demos.items():
            print(f"the demo on {t.upper()}: {d['rtf']:.2f}x real time ({d['task']})")
        same = demos["lcm"]["state"] == demos["dds"]["state"] and demos["lcm"]["session"] == demos["dds"]["session"]
        print(f"the same state and session digests on both: {same}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
