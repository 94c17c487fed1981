"""Benchmark: lockstep frame overhead (no physics) against a raw LCM round trip.

For 1, 2, 4 and 8 participants (Python, then C++) the C++ clock master runs FRAMES bare
frames (only the lockstep protocol: clock out, acks back, no other traffic) and reports
the wall time per frame. In the same run, two Python processes measure a raw LCM round
trip (publish, echo, receive) of a message the size of a clock. Each overhead is printed
beside that round trip as a ratio. Every figure is the median of REPEATS runs, taken in
an interleaved order so that a slow phase of the machine does not favour one figure.
Everything runs in a private network namespace. Every configuration runs twice: with the
bus authenticated (every message signed and verified with the deployment's key, the
default; docs/security.md) and without a key, so the cost of authentication is the
difference within one run.

Run: make bench   (or: .venv/bin/python bench/lockstep_overhead.py [--frames N])
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
from pathlib import Path

from plots import IMAGES
from skillbus import paths
from skillbus.lockstep_session import python_participant_argv
from skillbus.netns import Sandbox, last_json

HERE = Path(__file__).resolve().parent


def summary(proc) -> dict:
    s = last_json(proc.stdout())
    if s is None:
        raise RuntimeError(f"{proc.name} printed no summary: {proc.stderr()[-500:]}")
    return s


NO_KEY = {"SKILLBUS_KEY_FILE": "none"}


def raw_round_trip(box: Sandbox, n: int, size: int, via: str = "lcm") -> dict:
    pong = box.start(f"pong-{via}", [sys.executable, HERE / "pingpong.py", via, "pong"], env=NO_KEY)
    ping = box.start(f"ping-{via}", [sys.executable, HERE / "pingpong.py", via, "ping", str(n), str(size)], env=NO_KEY)
    box.wait(ping, 120)
    box.kill(pong)
    box.wait(pong, 10)
    return summary(ping)


def lockstep(box: Sandbox, n: int, lang: str, frames: int, signed: bool) -> dict:
    names = [f"p{i}" for i in range(n)]
    env = None if signed else NO_KEY
    clock = box.start(f"clock-{lang}{n}", [paths.binary("sb_clock"), "--frames", str(frames),
                                           "--participants", ",".join(names)], env=env)
    parts = []
    for name in names:
        argv = (python_participant_argv(name, "--bare") if lang == "py"
                else [paths.binary("sb_demo_participant"), "--name", name, "--bare"])
        parts.append(box.start(f"{lang}{n}-{name}", argv, env=env))
    box.wait(clock, 300)
    for p in parts:
        box.wait(p, 30)
    s = summary(clock)
    if not s["ok"]:
        raise RuntimeError(s["error"])
    return s


PLOT = IMAGES / "bench_lockstep.png"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=3000)
    ap.add_argument("--round-trips", type=int, default=3000)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--no-plot", action="store_true")
    args = ap.parse_args()
    configs = [(lang, n) for lang in ("py", "cpp") for n in (1, 2, 4, 8)]
    rt_runs: list[dict] = []
    bus_rt_runs: list[dict] = []
    per_config: dict[tuple[str, int, bool], list[float]] = {(*c, a): [] for c in configs for a in (True, False)}
    with Sandbox() as box:
        for _ in range(args.repeats):
            # A clock for one participant is ~90 bytes; the round trip uses the same size.
            rt_runs.append(raw_round_trip(box, args.round_trips, 96))
            bus_rt_runs.append(raw_round_trip(box, args.round_trips, 96, via="bus"))
            for lang, n in configs:
                for signed in (True, False):
                    per_config[(lang, n, signed)].append(lockstep(box, n, lang, args.frames, signed)["us_per_frame"])
    rt = {k: statistics.median(r[k] for r in rt_runs) for k in ("mean_us", "median_us", "p99_us")}
    bus_rt = {k: statistics.median(r[k] for r in bus_rt_runs) for k in ("mean_us", "median_us", "p99_us")}
    rows = [(lang, n, statistics.median(per_config[(lang, n, True)]), statistics.median(per_config[(lang, n, False)]))
            for lang, n in configs]
    print(f"lockstep frame overhead, {args.frames} bare frames each, median of {args.repeats} ({platform.machine()}, "
          f"{len(os.sched_getaffinity(0))} cores, {box.mode})")
    print(f"raw Python LCM round trip (96 B, no key): mean {rt['mean_us']:.1f} us, median {rt['median_us']:.1f} us, "
          f"p99 {rt['p99_us']:.1f} us")
    print(f"the same through skillbus's bus (no key):   mean {bus_rt['mean_us']:.1f} us, median {bus_rt['median_us']:.1f} us, "
          f"p99 {bus_rt['p99_us']:.1f} us")
    # Ratios to the round trip's median: its mean is inflated by the tail (a few slow
    # round trips on a shared machine), which flattered every ratio.
    base = rt["median_us"]
    print(f"{'participants':>12} {'language':>8} {'us/frame':>9} {'ratio to median round trip':>27} "
          f"{'no key us/frame':>16} {'authentication':>15}")
    for lang, n, us, bare in rows:
        print(f"{n:>12} {('Python' if lang == 'py' else 'C++'):>8} {us:>9.1f} {us / base:>27.2f} "
              f"{bare:>16.1f} {us - bare:>+12.1f} us")
    for n, limit in ((4, 2.5), (8, 3.0)):
        us = next(u for lang, k, u, _ in rows if lang == "py" and k == n)
        print(f"target ({n} Python participants within {limit}x of one raw Python round trip's median): "
              f"{'met' if us <= limit * base else 'NOT met'} ({us / base:.2f}x)")
    if not args.no_plot:
        plot(rows, base)
        print(f"plot: {PLOT.relative_to(PLOT.parents[2])}")
    return 0


def plot(rows: list, base: float) -> None:
    """us per frame against participants, each language with and without a key, and the
    round trip's median: how the frame's cost grows."""
    from plots import figure  # (matplotlib is loaded only to draw)
    with figure(PLOT, "Lockstep frame overhead", "participants", "us per bare frame (median)") as ax:
        for lang, name in (("py", "Python"), ("cpp", "C++")):
            mine = [r for r in rows if r[0] == lang]
            ax.plot([r[1] for r in mine], [r[2] for r in mine], "o-", label=f"{name} participants, signed")
            ax.plot([r[1] for r in mine], [r[3] for r in mine], "o--", label=f"{name} participants, no key")
        ax.axhline(base, color="grey", linestyle=":", label="raw Python LCM round trip (median)")
        ax.set_xticks([1, 2, 4, 8])

if __name__ == "__main__":
    sys.exit(main())
