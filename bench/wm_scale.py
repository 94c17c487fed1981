"""Benchmark: the world model at scale, 10,000 and 100,000 elements side by side.

For each size, in one run: a data directory is made (the scene of bench/wm_query.py
loaded through wm.load_scene, which writes a snapshot, then 500 commits in the journal);
then the server is started again from it and measured:

  start        from the process's start to its "serving" line (snapshot + journal replay)
  server RSS   VmRSS of the server after the start, and VmHWM (its peak) at the end
  query        every product (type skiros:Product with subclasses, whole elements), paged
               by the Python client (skillbus.world.client.query_all)
  replica      a new Python process: WorldModelInterface(...) (snapshot pages and the
               change stream); its time and the process's VmRSS
  commit       2,000 durable commits (one property update each, RPC wm.commit) with the
               default --snapshot-every (1000): the journal holds 500 records when they
               start, so snapshots are written after commits 500 and 1500; p50, p99, max

Prints a table (10k beside 100k, and the targets) and one JSON line.

Run: .venv/bin/python bench/wm_scale.py [--sizes 10000,100000] [--commits 2000]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

TARGETS = {"start_s": 2.0, "server_rss_mb": 300.0, "replica_s": 5.0, "commit_p99_ms": 5.0}
PRELOAD_COMMITS = 500


# ---------------------------------------------------------------- in the sandbox

def _rpc():
    from skillbus.bus import open_bus
    from skillbus.rpc import RpcClient
    return RpcClient(open_bus(), "WM", "wm-scale")


def _update_txn(i: int, eid: str):
    from skillbus.msgs import header_t, wm_op_t, wm_txn_t
    from skillbus.world.convert import op
    from skillbus.world.element import Element
    e = Element(eid.rsplit("-", 1)[0], "moved", eid)
    e.setProperty("skiros:PositionX", 0.001 * i)
    e.setProperty("skiros:PositionY", 0.0)
    e.setProperty("skiros:PositionZ", 0.02)
    e.setProperty("skiros:Size", 0.05)
    t = wm_txn_t()
    t.header = header_t()
    t.client_id, t.request_id, t.expected_version = "wm-scale", i, -1
    t.ops, t.num_ops = [op(wm_op_t.UPDATE_ELEMENT, element=e)], 1
    return t


def client_load(scene_path: str, commits: int) -> dict:
    from skillbus.msgs import wm_commit_t, wm_scene_t
    rpc = _rpc()
    req = wm_scene_t()
    req.path = scene_path
    t = time.perf_counter()
    rep = rpc.call("load_scene", req, wm_scene_t, timeout=600)
    load_s = time.perf_counter() - t
    for i in range(1, commits + 1):
        rpc.call("commit", _update_txn(i, "skiros:Cube-201"), wm_commit_t, timeout=60)
    return {"load_s": load_s, "version": rep.version}


def client_measure(commits: int, first_request: int) -> dict:
    from skillbus.msgs import wm_commit_t, wm_elements_t, wm_query_t
    from skillbus.rpc import RpcError
    from skillbus.world import client as wclient
    rpc = _rpc()
    out: dict = {}
    q = wm_query_t()
    q.type = "skiros:Product"
    t = time.perf_counter()
    try:
        if hasattr(wclient, "query_all"):
            from skillbus.world.wire import decode_elements
            found = wclient.query_all(
                lambda req, timeout: decode_elements(rpc.call_raw("query", req.encode(), timeout=timeout)), q)
            out["query_hits"] = len(found)
        else:  # the code before paging: one reply with everything
            out["query_hits"] = len(rpc.call("query", q, wm_elements_t, timeout=60).elements)
        out["query_s"] = time.perf_counter() - t
    except RpcError as e:
        out["query_s"], out["query_error"] = None, str(e)[:300]
    lat = []
    for i in range(first_request, first_request + commits):
        t = time.perf_counter()
        rpc.call("commit", _update_txn(i, "skiros:Cube-201"), wm_commit_t, timeout=60)
        lat.append(time.perf_counter() - t)
    lat.sort()
    out["commit_p50_ms"] = statistics.median(lat) * 1e3
    out["commit_p99_ms"] = lat[min(len(lat) - 1, int(len(lat) * 0.99))] * 1e3
    out["commit_max_ms"] = lat[-1] * 1e3
    out["commits_over_5ms"] = sum(1 for x in lat if x > 0.005)
    return out


def rss_mb(pid: int | str = "self", key: str = "VmRSS") -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(key + ":"):
            return int(line.split()[1]) / 1024
    return float("nan")


def client_replica() -> dict:
    from skillbus.bus import open_bus
    from skillbus.world import WorldModelInterface
    before = rss_mb()
    t = time.perf_counter()
    w = WorldModelInterface(open_bus(), "wm-scale-replica", timeout=30)
    s = time.perf_counter() - t
    return {"replica_s": s, "replica_rss_mb": rss_mb(), "python_rss_before_mb": before,
            "replica_elements": len(w._elements), "replica_version": w.version}


# ---------------------------------------------------------------- the driver

def server_pid(popen_pid: int) -> int:
    """The wm_server process: the sandbox's nsenter may run it as its child."""
    pid = popen_pid
    for _ in range(3):
        if Path(f"/proc/{pid}/comm").read_text().strip() == "wm_server":
            return pid
        kids = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
        if not kids:
            break
        pid = int(kids[0])
    return pid


def run_size(n: int, commits: int, tmp: Path) -> dict:
    from skillbus import paths
    from skillbus.netns import Sandbox, last_json
    from wm_query import make_scene
    data = tmp / f"data{n}"
    # (a request names a scene of the server's DATA/scenes, never a path)
    (data / "scenes").mkdir(parents=True, exist_ok=True)
    scene = data / "scenes" / f"scene{n}.ttl"
    scene.write_text(make_scene(n))
    server_bin = paths.build_dir() / "wm_server" / "wm_server"
    me = [sys.executable, str(Path(__file__).resolve())]
    res: dict = {"elements": n}

    def run_client(box, name, args, timeout, required=True):
        p = box.start(name, me + args)
        try:
            box.wait(p, timeout)
        except TimeoutError:
            pass
        got = last_json(p.stdout())
        if got is None:
            if required:
                raise SystemExit(f"{name} failed: {p.stderr()[-3000:]}")
            lines = [x for x in p.stderr().strip().splitlines() if x.strip()]
            return {f"{name}_error": lines[-1][:300] if lines else "no output"}
        return got

    with Sandbox() as box:  # make the data directory: a snapshot and a journal
        server = box.start("wm-load", [server_bin, "--wall-clock", "--data", data])
        server.wait_for("serving", 30)
        res.update(run_client(box, "load", ["load", scene.stem, str(PRELOAD_COMMITS)], 1200))
        box.kill(server, 15)
        box.wait(server, 60)
    sizes = {f: (data / f).stat().st_size for f in ("snapshot.bin", "journal.bin")}
    res["snapshot_mb"] = sizes["snapshot.bin"] / 1e6
    with Sandbox() as box:
        t = time.perf_counter()
        server = box.start("wm", [server_bin, "--wall-clock", "--data", data])
        server.wait_for("serving", 300, interval=0.005)
        res["start_s"] = time.perf_counter() - t
        pid = server_pid(server.popen.pid)
        time.sleep(0.2)
        res["server_rss_mb"] = rss_mb(pid)
        res.update(run_client(box, "replica", ["replica"], 600, required=False))
        res.update(run_client(box, "measure", ["measure", str(commits), str(PRELOAD_COMMITS + 1)], 1200))
        res["server_rss_end_mb"] = rss_mb(pid)
        res["server_hwm_mb"] = rss_mb(pid, "VmHWM")
    return res


def fmt(v, unit="", nd=2) -> str:
    if v is None:
        return "no reply"
    return f"{v:.{nd}f}{unit}"


def main() -> int:
    if len(sys.argv) > 1 and sys.argv[1] in ("load", "measure", "replica"):
        cmd = sys.argv[1]
        if cmd == "load":
            r = client_load(sys.argv[2], int(sys.argv[3]))
        elif cmd == "measure":
            r = client_measure(int(sys.argv[2]), int(sys.argv[3]))
        else:
            r = client_replica()
        print(json.dumps(r), flush=True)
        return 0
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="10000,100000")
    ap.add_argument("--commits", type=int, default=2000)
    args = ap.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    results = []
    with tempfile.TemporaryDirectory(prefix="wm-scale-") as tmp:
        for n in sizes:
            results.append(run_size(n, args.commits, Path(tmp)))
    rows = [
        ("snapshot file", "snapshot_mb", " MB", 1, None),
        ("server start (snapshot + journal)", "start_s", " s", 2, "start_s"),
        ("server RSS after start", "server_rss_mb", " MB", 0, "server_rss_mb"),
        ("server RSS peak (VmHWM)", "server_hwm_mb", " MB", 0, None),
        ("every product, paged (query_all)", "query_s", " s", 2, None),
        ("new Python replica", "replica_s", " s", 2, "replica_s"),
        ("  its process's RSS", "replica_rss_mb", " MB", 0, None),
        ("commit p50", "commit_p50_ms", " ms", 2, None),
        ("commit p99 (snapshots written)", "commit_p99_ms", " ms", 2, "commit_p99_ms"),
        ("commit max", "commit_max_ms", " ms", 2, None),
    ]
    print(f"world model at scale, {args.commits} commits, {time.strftime('%Y-%m-%d')}")
    print(f"{'':<36}" + "".join(f"{r['elements']:>14,}" for r in results) + f"{'target':>12}")
    for name, key, unit, nd, target in rows:
        line = f"{name:<36}" + "".join(f"{fmt(r.get(key), unit, nd):>14}" for r in results)
        if target:
            line += f"{'< ' + fmt(TARGETS[target], unit, 0 if unit == ' MB' else 0):>12}"
        print(line)
    big = results[-1]
    verdict = []
    for key, limit in TARGETS.items():
        v = big.get(key)
        verdict.append(f"{key} {'met' if v is not None and v < limit else 'NOT met'}")
    print(f"targets at {big['elements']:,}: " + ", ".join(verdict))
    for r in results:
        for what in ("query", "replica"):
            if r.get(f"{what}_error"):
                print(f"{what} at {r['elements']:,}: {r[f'{what}_error']}")
    print(json.dumps({"bench": "wm_scale", "date": time.strftime("%Y-%m-%d"), "results": results}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
