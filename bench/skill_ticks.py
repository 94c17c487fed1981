"""Benchmarks of the skill manager, each beside its peers measured in the same run.

(a) Tick overhead of a 1,000-node tree of trivial always-succeeding C++ leaves under a
    Serial node (our tree engine, bench/tree_tick_bench.cpp), beside BehaviorTree.CPP
    (the behaviortreepy wheel: a Sequence of 1,000 AlwaysSuccess from XML, one Python
    call per tick) and py_trees (a Sequence without memory of 1,000 Success behaviours).
    Targets: no slower than BehaviorTree.CPP, at least 50x faster than py_trees.
(b) The round trip of one Python primitive tick through the manager's code
    (bench/tick_rtt_bench.cpp: a RemotePrimitive ticking a skill process over LCM),
    beside a raw Python LCM round trip (bench/pingpong.py). Targets: the median within
    1.5x of the round trip's median; the tick's p99 within 3x of its median.
(c) How the manager's ticking grows with concurrent tasks: 1, 10, 100 and 1,000 tasks of
    an always-running Python primitive, started through the real manager (wall clock,
    25 Hz): the ticks each task gets a second, read from its progress messages, beside
    the 25 Hz asked for. Writes docs/images/bench_tasks.png.

Run: .venv/bin/python bench/skill_ticks.py   (in `make bench`)
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

from plots import IMAGES
from skillbus import paths
from skillbus.netns import Sandbox, last_json

HERE = Path(__file__).resolve().parent
LEAVES, TICKS = 1000, 2000
ROUNDS = 3  # tick round trips of each kind, each beside its raw round trip


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


NO_KEY = {"SKILLBUS_KEY_FILE": "none"}


def tick_round_trip(ticks: int, signed: bool, native: bool = True,
                    cores: tuple[str, str] | None = None) -> tuple[dict, dict]:
    """The raw LCM round trip (LCM's Python module: no key) and the tick, with the
    deployment's key (as the system runs) or without one (like for like with LCM); with
    `native` False the skill process signs and verifies in Python (SKILLBUS_NATIVE=0).
    `cores`: where the asking end (ping, the manager's node) and the answering end (pong,
    the skill process) run, both pairs alike (taskset); None leaves it to the kernel."""
    env = {} if signed else dict(NO_KEY)
    if not native:
        env["SKILLBUS_NATIVE"] = "0"
    asking, answering = (["taskset", "--cpu-list", c] for c in cores) if cores else ([], [])
    with Sandbox() as box:
        pong = box.start("pong", [*answering, sys.executable, HERE / "pingpong.py", "lcm", "pong"], env=NO_KEY)
        ping = box.start("ping", [*asking, sys.executable, HERE / "pingpong.py", "lcm", "ping", str(ticks), "200"],
                         env=NO_KEY)
        box.wait(ping, 120)
        box.kill(pong)
        raw = last_json(ping.stdout())
        # tick_rtt_bench plays the manager's node that ticks the process: no manager (a real
        # one would end the skill instances it did not start).
        proc = box.start("skills", [*answering, sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "bench",
                                    "--library", "spin_skills", "--standalone"], env={"PYTHONPATH": str(HERE), **env})
        try:
            proc.wait_for("without a skill manager", 60)
        except RuntimeError as e:
            raise SystemExit(f"the skill process did not start: {e}")
        rtt = box.start("rtt", [*asking, paths.build_dir() / "bench" / "tick_rtt_bench", "SKPROC_BENCH", "spin",
                                str(ticks)], env=env)
        box.wait(rtt, 120)
        got = last_json(rtt.stdout())
        if got is None or "error" in got:
            raise SystemExit(f"tick_rtt_bench failed: {rtt.stdout()} {rtt.stderr()[-2000:]}")
        return raw, got


GROWTH = (1, 10, 100, 1000)
PLOT = IMAGES / "bench_tasks.png"

TASKS_CLIENT = r'''
import json, sys, time
from skillbus.bus import open_bus, channel
from skillbus.msgs import decode, skill_progress_t, skill_start_t, skill_task_t
from skillbus.rpc import RpcClient
counts = [int(x) for x in sys.argv[1].split(",")]
window = float(sys.argv[2])
bus = open_bus()
client = RpcClient(bus, "SKILL", "bench")
latest = {}  # task -> its latest tick count
def on_progress(ch, data):
    p = decode(skill_progress_t, data)
    if p is not None and p.task in latest:
        latest[p.task] = max(latest[p.task], p.tick)
bus.subscribe(channel("SB_SKILL_PROGRESS"), on_progress)
def pump(seconds):
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        bus.handle(0.02)
out = {}
pump(3.0)  # (the manager's wall clock settles after the start)
for n in counts:
    latest.clear()
    started = []
    for _ in range(n):
        req = skill_start_t(); req.type = "Spin"
        started.append(client.call("start", req, skill_task_t, timeout=10).task)
        latest[started[-1]] = 0
    pump(1.0)  # (settled: every task started and ticking)
    before, t0 = dict(latest), time.monotonic()
    pump(window)
    elapsed = time.monotonic() - t0
    rates = sorted((latest[t] - before[t]) / elapsed for t in started)
    out[n] = {"median_hz": rates[len(rates) // 2], "min_hz": rates[0]}
    for t in started:
        req = skill_start_t(); req.task = t
        try:
            client.call("stop", req, skill_task_t, timeout=10)
        except Exception:
            pass
    time.sleep(0.5)
print(json.dumps(out))
'''


def task_growth(window_s: float = 4.0) -> dict:
    with Sandbox() as box:
        box.start("skill_mgr", [paths.build_dir() / "skill_mgr" / "skill_mgr", "--wall-clock"])
        proc = box.start("skills", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "bench",
                                    "--library", "spin_skills", "--register-timeout", "60"], env={"PYTHONPATH": str(HERE)})
        proc.wait_for("registered", 60)
        client = box.start("tasks", [sys.executable, "-c", TASKS_CLIENT, ",".join(map(str, GROWTH)), str(window_s)])
        box.wait(client, 900)
        got = last_json(client.stdout())
        if got is None:
            raise SystemExit(f"the task client failed: {client.stderr()[-2000:]}")
        return {int(k): v for k, v in got.items()}


def plot_tasks(growth: dict) -> None:
    from plots import figure  # (matplotlib is loaded only to draw)
    n = sorted(growth)
    with figure(PLOT, "The skill manager's ticking as tasks grow",
                "concurrent tasks (an always-running Python primitive each)", "ticks per second", log_x=True) as ax:
        ax.plot(n, [growth[k]["median_hz"] for k in n], "o-", label="ticks a second each task gets (median)")
        ax.plot(n, [growth[k]["min_hz"] for k in n], "o--", label="the least served task")
        ax.axhline(25, color="grey", linestyle=":", label="asked for: 25 Hz")

def main() -> int:
    a = statistics.median(ours() for _ in range(3))
    b = statistics.median(behaviortree_cpp() for _ in range(3))
    c = py_trees_figure()
    print(f"(a) tick of a {LEAVES}-leaf tree (Serial/Sequence of always-succeeding leaves), us per tick")
    print(f"    skillbus tree engine   {a:10.1f}")
    print(f"    BehaviorTree.CPP       {b:10.1f}   ratio BT.CPP/ours  {b / a:6.2f}  (target >= 1)")
    print(f"    py_trees               {c:10.1f}   ratio py_trees/ours {c / a:6.1f}  (target >= 50)")
    # Rounds, each tick beside a raw round trip measured just before it in the same
    # sandbox: the shared machine's speed drifts within a minute (the raw round trip's
    # median moved from 68 to 89 us between two runs), so each ratio is taken within its
    # round and the median of the rounds' ratios is the figure.
    kinds = (("signed", dict(signed=True)), ("without a key", dict(signed=False)),
             ("Python auth", dict(signed=True, native=False)))
    rounds = {name: [tick_round_trip(2000, **kw) for _ in range(ROUNDS)] for name, kw in kinds}

    def ratio_of(name: str) -> float:
        return statistics.median(t["median_us"] / raw["median_us"] for raw, t in rounds[name])

    def figure(name: str, key: str) -> float:
        return statistics.median(t[key] for _, t in rounds[name])

    raw_median = statistics.median(raw["median_us"] for name, _ in kinds for raw, _ in rounds[name])
    print(f"(b) one Python primitive tick through the manager, us (median / p99; medians of {ROUNDS} rounds, each "
          f"beside a raw round trip)")
    print(f"    manager -> skill process -> manager, signed (as deployed)  {figure('signed', 'median_us'):8.1f} / "
          f"{figure('signed', 'p99_us'):8.1f}   {ratio_of('signed'):.2f}x the round trip")
    print(f"    the same, signed and verified in Python (SKILLBUS_NATIVE=0) {figure('Python auth', 'median_us'):7.1f} / "
          f"{figure('Python auth', 'p99_us'):8.1f}   {ratio_of('Python auth'):.2f}x")
    print(f"    the same without a key                                    {figure('without a key', 'median_us'):8.1f} / "
          f"{figure('without a key', 'p99_us'):8.1f}   {ratio_of('without a key'):.2f}x")
    raws = ", ".join(f"{raw['median_us']:.0f}" for name, _ in kinds for raw, _ in rounds[name])
    print(f"    raw Python LCM round trip (200 B; LCM signs nothing)       {raw_median:8.1f}   (rounds: {raws})")
    for name in ("without a key", "signed"):
        ratio = ratio_of(name)
        tail = statistics.median(t["p99_us"] / t["median_us"] for _, t in rounds[name])
        print(f"    target, {name}: the tick's median within 1.5x of the round trip's median: "
              f"{'met' if ratio <= 1.5 else 'NOT met'} ({ratio:.2f}x); its p99 within 3x of its median: "
              f"{'met' if tail <= 3 else 'NOT met'} ({tail:.2f}x)")
    # Where the two ends run moves both round trips by more than the tick's own work: a
    # message that wakes a process on the other core costs its sender a wake-up across
    # cores (an inter-processor interrupt; about 20 us each way on this machine), one on
    # the same core does not. Both pairs placed alike, signed, one round each (not targets).
    print("    placed (signed; the asking end's core / the answering end's; one round each): ", end="")
    placed = []
    for cores in (("0", "0"), ("0", "1"), ("1", "0")):
        if not set(map(int, cores)) <= os.sched_getaffinity(0):
            continue
        raw, t = tick_round_trip(2000, signed=True, cores=cores)
        placed.append(f"{cores[0]}/{cores[1]}: tick {t['median_us']:.0f} us, raw {raw['median_us']:.0f} us, "
                      f"{t['median_us'] / raw['median_us']:.2f}x")
    print("; ".join(placed) or "fewer than 2 cores")
    growth = task_growth()
    print("(c) ticks a second per task (median / least served), asked for 25 Hz, by concurrent tasks")
    for n in sorted(growth):
        print(f"    {n:>5} tasks  {growth[n]['median_hz']:6.1f} / {growth[n]['min_hz']:6.1f}")
    plot_tasks(growth)
    print(f"    plot: {PLOT.relative_to(HERE.parent)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
