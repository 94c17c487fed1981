"""Episode generation's throughput: `skillbus generate` of the drawer task
(deploy/generate/drawer.yaml) with 1 worker and with 2 workers, the same episodes (same
seed) each time, rounds interleaved. Each episode is a whole system in lockstep (physics,
world model, skill manager, motion service, CANopen gripper, skill process, logger).

Prints episodes per hour, per core, the cores the run kept busy and the episodes per CPU
hour (CPU seconds of every process of every episode, from getrusage of the children),
the sim seconds per wall second (the real-time factor over all episodes), and the
scaling from 1 to 2 workers (the throughputs' ratio; 2.0 would be perfect on 2 idle
cores if one episode used one core). Target (issue "Manipulation-command skills"): reported, with the
scaling; the episodes' digests must be the same in every run (the work is the same).

Run: .venv/bin/python bench/generate_scaling.py [--episodes 8] [--rounds 2]   (in `make bench`)
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "deploy" / "generate" / "drawer.yaml"


def run(workers: int, episodes: int, seed: int) -> dict:
    with tempfile.TemporaryDirectory(prefix="sb-gen-bench-") as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.monotonic()
        p = subprocess.run([sys.executable, "-m", "skillbus.cli", "generate", str(CONFIG), "--episodes", str(episodes),
                            "--seed", str(seed), "--workers", str(workers), "--out", str(Path(tmp) / "ds"), "--json"],
                           capture_output=True, text=True, timeout=3600)
        wall = time.monotonic() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)  # every process of every episode (all waited for)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        if p.returncode != 0:
            raise SystemExit(f"generate with {workers} worker(s) failed:\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}")
        r = json.loads(p.stdout.strip().splitlines()[-1])
    eps = r["episodes"]
    sim = sum(e["sim_s"] for e in eps.values())
    return {"workers": workers, "wall_s": wall, "cpu_s": cpu, "episodes": len(eps), "successes": r["successes"],
            "retried": r["retried"], "sim_s": sim, "digests": sorted(e["session_digest"] for e in eps.values())}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--json", default=None, help="also write the figures here")
    args = ap.parse_args()
    cores = os.cpu_count() or 1
    rows: dict[int, list[dict]] = {1: [], 2: []}
    for _ in range(args.rounds):
        for w in (1, 2):
            rows[w].append(run(w, args.episodes, args.seed))
    digests = {tuple(r["digests"]) for rs in rows.values() for r in rs}
    print(f"episode generation: the drawer task, {args.episodes} episodes per run, {args.rounds} round(s), "
          f"{cores} core(s)")
    print(f"{'workers':>8} {'wall s':>8} {'episodes/h':>11} {'per core':>9} {'cores busy':>11} "
          f"{'per CPU-hour':>13} {'sim s / wall s':>15} {'success':>8}")
    out = {}
    for w, rs in rows.items():
        wall = statistics.median(r["wall_s"] for r in rs)
        eph = 3600.0 * args.episodes / wall
        rtf = statistics.median(r["sim_s"] / r["wall_s"] for r in rs)
        per_core = eph / min(w, cores)
        ok = sum(r["successes"] for r in rs) / sum(r["episodes"] for r in rs)
        busy = statistics.median(r["cpu_s"] / r["wall_s"] for r in rs)
        per_cpu_hour = 3600.0 * args.episodes / statistics.median(r["cpu_s"] for r in rs)
        out[w] = {"wall_s": wall, "episodes_per_hour": eph, "per_core": per_core, "cores_busy": busy,
                  "per_cpu_hour": per_cpu_hour, "rtf": rtf, "success": ok}
        print(f"{w:>8} {wall:>8.1f} {eph:>11.0f} {per_core:>9.0f} {busy:>11.2f} {per_cpu_hour:>13.0f} {rtf:>15.1f} "
              f"{ok * 100:>7.0f}%")
    scaling = out[2]["episodes_per_hour"] / out[1]["episodes_per_hour"]
    print(f"scaling from 1 to 2 workers: {scaling:.2f}x (2.00 would be perfect)")
    same = len(digests) == 1
    print(f"the episodes' session digests in every run: {'the same' if same else 'DIFFERENT'}: "
          f"{'met' if same else 'not met'}")
    if args.json:
        Path(args.json).write_text(json.dumps({"rows": out, "scaling": scaling, "same_digests": same}, indent=1))
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
