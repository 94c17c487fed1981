"""Benchmark: lockstep frame overhead (no physics) against a raw LCM round trip.

For 1, 2, 4 and 8 participants (Python, then C++) the C++ clock master runs FRAMES bare
frames (only the lockstep protocol: clock out, acks back, no other traffic) and reports
the wall time per frame. In the same run, two Python processes measure a raw LCM round
trip (publish, echo, receive) of a message the size of a clock. Each overhead is printed
beside that round trip as a ratio. Every figure is the median of REPEATS runs, taken in
an interleaved order so that a slow phase of the machine does not favour one figure.
Everything runs in a private network namespace.

Run: make bench   (or: .venv/bin/python bench/lockstep_overhead.py [--frames N])
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
from pathlib import Path

from skillbus import paths
from skillbus.lockstep_session import python_participant_argv
from skillbus.netns import Sandbox, last_json

HERE = Path(__file__).resolve().parent


def summary(proc) -> dict:
    s = last_json(proc.stdout())
    if s is None:
        raise RuntimeError(f"{proc.name} printed no summary: {proc.stderr()[-500:]}")
    return s


def raw_round_trip(box: Sandbox, n: int, size: int) -> dict:
    pong = box.start("pong", [sys.executable, HERE / "pingpong.py", "pong"])
    ping = box.start("ping", [sys.executable, HERE / "pingpong.py", "ping", str(n), str(size)])
    box.wait(ping, 120)
    box.kill(pong)
    box.wait(pong, 10)
    return summary(ping)


def lockstep(box: Sandbox, n: int, lang: str, frames: int) -> dict:
    names = [f"p{i}" for i in range(n)]
    clock = box.start(f"clock-{lang}{n}", [paths.binary("sb_clock"), "--frames", str(frames),
                                           "--participants", ",".join(names)])
    parts = []
    for name in names:
        argv = (python_participant_argv(name, "--bare") if lang == "py"
                else [paths.binary("sb_demo_participant"), "--name", name, "--bare"])
        parts.append(box.start(f"{lang}{n}-{name}", argv))
    box.wait(clock, 300)
    for p in parts:
        box.wait(p, 30)
    s = summary(clock)
    if not s["ok"]:
        raise RuntimeError(s["error"])
    return s


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=3000)
    ap.add_argument("--round-trips", type=int, default=3000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    configs = [(lang, n) for lang in ("py", "cpp") for n in (1, 2, 4, 8)]
    rt_runs: list[dict] = []
    per_config: dict[tuple[str, int], list[float]] = {c: [] for c in configs}
    with Sandbox() as box:
        for _ in range(args.repeats):
            # A clock for one participant is ~90 bytes; the round trip uses the same size.
            rt_runs.append(raw_round_trip(box, args.round_trips, 96))
            for lang, n in configs:
                per_config[(lang, n)].append(lockstep(box, n, lang, args.frames)["us_per_frame"])
    rt = {k: statistics.median(r[k] for r in rt_runs) for k in ("mean_us", "median_us", "p99_us")}
    rows = [(lang, n, statistics.median(per_config[(lang, n)])) for lang, n in configs]
    print(f"lockstep frame overhead, {args.frames} bare frames each, median of {args.repeats} ({platform.machine()}, "
          f"{len(os.sched_getaffinity(0))} cores, {box.mode})")
    print(f"raw Python LCM round trip (96 B): mean {rt['mean_us']:.1f} us, median {rt['median_us']:.1f} us, "
          f"p99 {rt['p99_us']:.1f} us")
    print(f"{'participants':>12} {'language':>8} {'us/frame':>9} {'ratio to round trip':>20}")
    for lang, n, us in rows:
        print(f"{n:>12} {('Python' if lang == 'py' else 'C++'):>8} {us:>9.1f} {us / rt['mean_us']:>20.2f}")
    py4 = next(us for lang, n, us in rows if lang == "py" and n == 4)
    verdict = "met" if py4 <= 3 * rt["mean_us"] else "NOT met"
    print(f"target (4 Python participants within 3x of one raw Python round trip): {verdict} "
          f"({py4 / rt['mean_us']:.2f}x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
