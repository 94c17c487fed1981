"""What the console costs the lockstep run: the pick-and-place demo (ClearTable, every
process real, lockstep) without a console, and with `skillbus console` attached and a
client on its live feed (what a browser's page gets: every tree change, the 3D view's
frames, the world's versions), runs interleaved, each in a sandbox of its own. The page's
client is a Python process reading the feed: on this 2-core machine it competes with the
lockstep run for the cores, as a browser would, so its row shows the cost of a page, not
of the console.

Target (issue "The skillbus console"): the demo's real-time factor with a console
attached is within 5 % of without (the medians' ratio at least 0.95).

Run: .venv/bin/python bench/console_overhead.py [--rounds 3]   (in `make bench`)
"""

from __future__ import annotations

import argparse
import json
import re
import signal
import statistics
import sys
import tempfile
import time
from pathlib import Path

from skillbus.netns import Sandbox, last_json
from skillbus.system import programs, start

SETTLE_S = 3.0  # s between runs: the previous sandbox's processes are gone

# The live feed's client: counts events and bytes until the console goes away.
CLIENT = """
import json, sys
from websockets.sync.client import connect
events = size = 0
kinds = {}
try:
    base, _, query = sys.argv[1].partition("?")
    with connect(base.replace("http", "ws") + "api/live?" + query, max_size=None) as ws:
        print("connected", flush=True)
        for m in ws:
            events += 1; size += len(m)
            k = json.loads(m)["kind"]; kinds[k] = kinds.get(k, 0) + 1
except Exception:
    pass
print(json.dumps({"events": events, "bytes": size, "kinds": kinds}), flush=True)
"""


def run(tmp: Path, name: str, mode: str) -> dict:
    """One demo run; mode: "none", "console" (attached to the bus, no page open) or
    "page" (and a client on its live feed)."""
    run_dir = tmp / name
    run_dir.mkdir()
    with Sandbox(log_dir=run_dir / "logs") as box:
        client = console = None
        if mode != "none":
            console = box.start("console", [sys.executable, "-m", "skillbus.cli", "console", "--port", "0"])
            url = console.wait_for(re.compile(r"skillbus console: (http://\S+)"), 30, stream="stdout").group(1)
        if mode == "page":
            client = box.start("client", [sys.executable, "-c", CLIENT, url])
            client.wait_for("connected", 30, stream="stdout")
        procs = start(box, programs(run_dir), run_dir)
        box.wait(procs["sim"], 900)
        sim = last_json(procs["sim"].stdout())
        out = {"rtf": sim["real_time_factor"], "wall_s": sim["wall_time_s"], "sim_s": sim["sim_time_s"],
               "session_digest": sim["session_digest"]}
        if console is not None:
            box.kill(console, signal.SIGTERM)  # (the feed ends with it)
            box.wait(console, 30)
        if client is not None:
            box.wait(client, 30)
            out["feed"] = last_json(client.stdout())
        return out


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=6)
    args = ap.parse_args()
    modes = ("none", "console", "page")
    runs: dict[str, list[dict]] = {m: [] for m in modes}
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.rounds):
            # Interleaved, in an order that turns each round (a drift of the machine's speed,
            # or what the previous run leaves behind, hits all three alike), after a pause.
            for m in modes[i % 3:] + modes[:i % 3]:
                time.sleep(SETTLE_S)
                runs[m].append(run(Path(tmp), f"{m}{i}", m))
            print(f"round {i + 1}: without a console {runs['none'][-1]['rtf']:.2f}x real time; console attached "
                  f"{runs['console'][-1]['rtf']:.2f}x; and a page's live feed {runs['page'][-1]['rtf']:.2f}x "
                  f"({runs['page'][-1]['feed']})", flush=True)
    med = {m: statistics.median(r["rtf"] for r in runs[m]) for m in modes}
    same = len({r["session_digest"] for m in modes for r in runs[m]}) == 1
    ratio, page_ratio = med["console"] / med["none"], med["page"] / med["none"]
    print(f"median real-time factor: without a console {med['none']:.2f}x; console attached {med['console']:.2f}x "
          f"(ratio {ratio:.3f}); with a page's live feed too {med['page']:.2f}x (ratio {page_ratio:.3f}); the same "
          f"session digest in every run: {same}")
    print(f"target: with a console attached, the demo's real-time factor is within 5 % of without: "
          f"{'met' if ratio >= 0.95 else 'NOT met'} ({100 * (ratio - 1):+.1f} %)")
    print(json.dumps({"console_overhead": {"runs": runs, "median_rtf": med, "ratio": ratio, "page_ratio": page_ratio,
                                           "same_digest": same}}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
