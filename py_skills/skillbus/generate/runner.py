"""Episodes in parallel, and the dataset written in episode order.

Locally (the default) each episode runs in a worker process of its own
(skillbus.generate.worker: a PID namespace and a network namespace of its own), at most
``workers`` at a time, dispatched by concurrent.futures; on a Ray cluster (``--ray
ADDRESS``, or ``--ray local`` for a one-node Ray instance of this machine's) each episode
is a Ray task running the same worker process. An
episode whose worker died or whose recording is incomplete is run again (``retries``
times), then counted as broken with its reason: it never enters the dataset. Finished
episodes, successes and failures alike (each labelled), are written in the order of
their numbers as soon as every episode before them is settled, so the dataset is the
same whatever order the workers finish in.
"""

from __future__ import annotations

import concurrent.futures as cf
import os
import pickle
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from skillbus.generate.config import GenerateConfig, as_dict
from skillbus.generate.episode import WALL_SLACK_S
from skillbus.generate.lerobot import DatasetWriter
from skillbus.generate.uninterrupted import uninterrupted


@dataclass
class Summary:
    requested: int = 0
    written: int = 0
    successes: int = 0
    broken: list[dict[str, Any]] = field(default_factory=list)
    failures: Counter = field(default_factory=Counter)
    retried: int = 0
    retries: list[dict[str, Any]] = field(default_factory=list)  # why each retry was needed
    interrupted: bool = False
    wall_s: float = 0.0
    results: dict[int, dict[str, Any]] = field(default_factory=dict)  # request -> the written episode's meta

    def lines(self, workers: int) -> list[str]:
        rate = self.successes / self.written if self.written else 0.0
        per_hour = 3600.0 * self.written / self.wall_s if self.wall_s > 0 else 0.0
        out = [f"episodes: {self.written} written of {self.requested} requested, {len(self.broken)} broken, "
               f"{self.retried} retried",
               f"success rate: {rate * 100:.1f}% ({self.successes}/{self.written})",
               f"episodes per hour: {per_hour:.0f} on {workers} worker(s) ({per_hour / max(1, workers):.0f} per worker)"]
        for reason, n in self.failures.most_common():
            out.append(f"  failed {n}x: {reason}")
        for b in self.broken:
            out.append(f"  broken: episode {b['request']}: {b['error']}")
        for r in self.retries:
            out.append(f"  retried: episode {r['request']} (attempt {r['attempt']}): {r['error']}")
        return out


EXIT_MARK = "skillbus-worker-exit"


def worker_argv(cfg: GenerateConfig, seed: int, request: int, attempt: int, work: Path, out: Path) -> list[str]:
    # sh, the namespace's first process, says how the worker ended (unshare cannot pass a
    # SIGKILL on: it reports its own failure to raise it); when sh exits the kernel ends
    # the namespace and whatever of the episode is left in it.
    # setpriv: should generate itself be killed (kill -9), the kernel kills unshare, and
    # --kill-child then the episode's namespace; no episode outlives its run.
    return ["setpriv", "--pdeathsig", "KILL", "--",
            "unshare", "-rmpn", "--fork", "--mount-proc", "--kill-child", "--",
            "sh", "-c", f'"$@"; s=$?; echo "{EXIT_MARK} $s" >&2; exit $s', "sh",
            sys.executable, "-m", "skillbus.generate.worker", str(cfg.path), str(seed), str(request), str(attempt),
            str(work), str(out)]


def how_it_ended(returncode: int, log: str) -> str:
    """How a worker ended, from its exit status as its namespace's first process saw it.

    >>> how_it_ended(1, "...\\nskillbus-worker-exit 137\\n"), how_it_ended(1, "no mark")
    ('killed by signal 9', 'exit 1')
    """
    import re
    m = re.findall(EXIT_MARK + r" (\d+)", log)
    code = int(m[-1]) if m else returncode
    if code < 0:
        return f"killed by signal {-code}"
    return f"killed by signal {code - 128}" if code > 128 else f"exit {code}"


_live: set[subprocess.Popen] = set()  # the workers running now
_live_lock = threading.Lock()


def stop_workers() -> None:
    """Ends every running worker and its episode's namespace (SIGTERM to unshare, whose
    --kill-child then kills the namespace): for a SIGTERM that reached generate alone."""
    with _live_lock:
        for p in _live:
            if p.poll() is None:
                p.terminate()


# Beyond the episode's own bound on its session (max_sim_s + WALL_SLACK_S): the worker's
# start (its namespaces, the interpreter) and the end of its processes.
WORKER_SLACK_S = 120.0


def worker_time_limit(cfg: GenerateConfig) -> float:
    """How long a worker may take, wall clock, before it is killed and its episode counted
    as broken (and run again, as a crashed one is): a worker stuck past its episode's own
    limits must not hold the dataset's order for ever."""
    return cfg.max_sim_s + WALL_SLACK_S + WORKER_SLACK_S


def run_local(cfg: GenerateConfig, seed: int, request: int, attempt: int, work: Path) -> dict[str, Any]:
    out = work / f"result-{request:06d}-{attempt}.pkl"
    log = work / f"worker-{request:06d}-{attempt}.log"
    limit = worker_time_limit(cfg)
    with open(log, "wb") as f:
        p = subprocess.Popen(worker_argv(cfg, seed, request, attempt, work, out), stdout=f, stderr=subprocess.STDOUT)
        with _live_lock:
            _live.add(p)
        try:
            try:
                p.wait(timeout=limit)
            except subprocess.TimeoutExpired:
                p.kill()  # (unshare's --kill-child then ends the episode's namespace with it)
                p.wait(timeout=30)
                return {"error": f"the worker gave no result within {limit:.0f} s (killed)"}
        finally:
            with _live_lock:
                _live.discard(p)
    if not out.exists():
        text = log.read_text(errors="replace")
        how = how_it_ended(p.returncode, text)
        tail = "\n".join(x for x in text.splitlines() if EXIT_MARK not in x)[-400:].strip()
        return {"error": f"the worker ended without a result ({how})" + (f": {tail}" if tail else "")}
    r = pickle.loads(out.read_bytes())
    out.unlink()
    return r


def run_ray_task(cfg_path: str, seed: int, request: int, attempt: int) -> dict[str, Any]:
    """An episode as a Ray task: the same worker process as locally (its own PID and
    network namespaces, so a Ray worker that dies takes the episode's processes with it),
    in a folder of the node's own; the result travels back in Ray's object store. Every
    node needs skillbus and the config's files at the same paths."""
    import tempfile
    from skillbus.generate.config import load
    # A terminal's Ctrl-C reaches the whole process group, this worker too; the driver then
    # cancels the task as well (forced), and the two endings raced inside Ray: its core
    # worker in the driver aborted on a task completed twice ("Tried to complete task that
    # was not pending"), and generate exited 1 instead of 130. The driver alone ends a task.
    try:
        before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # (not the worker's main thread: nothing to hold off)
        before = None
    try:
        with tempfile.TemporaryDirectory(prefix="skillbus-episode-") as work:
            return run_local(load(cfg_path), seed, request, attempt, Path(work))
    finally:
        if before is not None:
            signal.signal(signal.SIGINT, before)


def generate(cfg: GenerateConfig, out: Path, episodes: int, seed: int, workers: int = 2, first: int = 0,
             ray: str | None = None, progress: Callable[[int, int], None] | None = None,
             keep_work: bool = False) -> Summary:
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    work = out / "work"
    work.mkdir(exist_ok=True)
    writer = DatasetWriter(out, cfg.fps)
    summary = Summary(requested=episodes)
    requests = list(range(first, first + episodes))
    attempts = {r: 0 for r in requests}
    settled: dict[int, dict[str, Any]] = {}
    next_to_write = 0
    t0 = time.monotonic()

    def settle(request: int, r: dict[str, Any]) -> bool:
        """True when the episode is settled (a result, or broken for good)."""
        if "error" in r:
            if attempts[request] < cfg.retries:
                summary.retries.append({"request": request, "attempt": attempts[request], "error": r["error"]})
                attempts[request] += 1
                summary.retried += 1
                return False
            summary.broken.append({"request": request, "error": r["error"]})
        settled[request] = r
        return True

    def flush() -> None:
        nonlocal next_to_write
        while next_to_write < len(requests) and requests[next_to_write] in settled:
            r = settled.pop(requests[next_to_write])
            next_to_write += 1
            if "error" in r:
                continue
            meta = {k: r[k] for k in ("request", "seed", "attempt", "success", "failure_reason", "task_result",
                                      "state_digest", "session_digest", "sim_s", "randomized", "segments")}
            meta["config"] = as_dict(cfg)["config"]
            with uninterrupted():  # written and counted, or neither
                writer.write_episode(r["episode"], cfg.instruction, meta)
                summary.written += 1
                summary.successes += bool(r["success"])
                if not r["success"]:
                    summary.failures[r["failure_reason"]] += 1
                summary.results[r["request"]] = meta
            if progress:
                progress(summary.written + len(summary.broken), episodes)

    try:
        if ray:
            _run_with_ray(cfg, seed, requests, attempts, workers, ray, settle, flush)
        else:
            _run_with_threads(cfg, seed, requests, attempts, workers, work, settle, flush)
        flush()
    except KeyboardInterrupt:
        # Ctrl-C reached the workers too (one process group): they end their episodes'
        # systems; nothing more starts, and what is written stays whole (the writer holds
        # the signal until the episode it is writing is complete).
        summary.interrupted = True
    summary.wall_s = time.monotonic() - t0
    if not keep_work:
        shutil.rmtree(work, ignore_errors=True)
    return summary


def _run_with_threads(cfg, seed, requests, attempts, workers, work, settle, flush) -> None:
    pool = cf.ThreadPoolExecutor(max_workers=max(1, workers))
    try:
        pending = {pool.submit(run_local, cfg, seed, r, 0, work): r for r in requests}
        while pending:
            done, _ = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for fut in done:
                request = pending.pop(fut)
                try:
                    r = fut.result()
                except Exception as e:  # (run_local itself failing: no worker could be started)
                    r = {"error": f"{type(e).__name__}: {e}"}
                if not settle(request, r):
                    pending[pool.submit(run_local, cfg, seed, request, attempts[request], work)] = request
            flush()
    except BaseException:  # Ctrl-C, SIGTERM, or the dataset refused an episode: no worker goes on
        stop_workers()  # Ctrl-C reached them already; a SIGTERM sent to generate alone did not
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)  # on Ctrl-C: nothing queued starts


def _run_with_ray(cfg, seed, requests, attempts, workers, address, settle, flush) -> None:
    import ray
    if not ray.is_initialized():
        if address == "local":  # a one-node cluster of this machine's (Ray 2.5x has no local mode any more)
            ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
        else:
            ray.init(address=address, log_to_driver=False)
    task = ray.remote(max_retries=0, num_cpus=1)(run_ray_task)
    pending = {task.remote(str(cfg.path), seed, r, 0): r for r in requests}
    try:
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            for ref in done:
                request = pending.pop(ref)
                try:
                    r = ray.get(ref)
                except Exception as e:  # a Ray worker that died mid-episode
                    r = {"error": f"the Ray worker failed: {type(e).__name__}: {e}"}
                if not settle(request, r):
                    pending[task.remote(str(cfg.path), seed, request, attempts[request])] = request
            flush()
    except BaseException:  # Ctrl-C, SIGTERM, or the dataset refused an episode: no task goes on
        for ref in pending:  # a forced cancel kills the Ray worker, and with it the episode's namespaces
            ray.cancel(ref, force=True)
        raise


def default_workers() -> int:
    return max(1, min(2, os.cpu_count() or 1))
