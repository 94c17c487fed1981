"""Crashes and power losses at random points of a write sequence, inside the test's
sandbox (tests/integration/test_journal_faults.py).

A writer thread commits elements labelled w0, w1, ... one transaction at a time through
RPC wm.commit, each with its own (client id, request id): a commit that gets no answer
is sent again, the same transaction, until it does, as a client does across a server
restart. At each point the driver lets the server acknowledge a random number of commits,
waits a random fraction of a millisecond into the next one, kills it with SIGKILL, and
then either leaves the files as the page cache has them (kill -9 alone) or rebuilds the
data directory as a power loss at that moment could leave it, from what the fsync shim
(tests/support/fsync_shim.c) recorded: each file up to the length of its last
fsync/fdatasync, the names of the directory's last fsync, plus nothing, a random prefix,
or zeros for what was written after the last sync. Then it restarts the server and checks
that it starts, at the version of every acknowledged commit (or one more: the commit in
flight may have been durable). Every acknowledgement must carry version i + 1 for w<i>
(the world starts empty), so a lost or doubled commit shows at the next one. At the end
the world must hold each acknowledged label once.

Usage: journal_fault_driver.py --points N --seed S --work DIR [--shim SO] [--snapshot-every K]
                               [--fsync-delay-us US]
Prints one JSON line: points, modes, acknowledged, survivors, torn tails cut, failures.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from skillbus import paths
from skillbus.bus import open_bus
from skillbus.msgs import header_t, wm_commit_t, wm_op_t, wm_txn_t
from skillbus.rpc import RpcClient, RpcError, RpcRemoteError, RpcTimeout
from skillbus.waiting import wait_until
from skillbus.world import Element, WorldModelInterface
from skillbus.world.convert import op

MODES = ("kill", "power-synced", "power-prefix", "power-zeros")
STARTED = re.compile(r"serving \S+ on \S+: version (\d+), (\d+) elements")


class Writer(threading.Thread):
    """Commits w0, w1, ... until stopped; `acked[i]` is the version of w<i>'s answer."""

    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.rpc = RpcClient(open_bus(), "WM", "fault-writer")
        self.acked: list[int] = []
        self.refused: list[str] = []
        self.cond = threading.Condition()
        self.stop = threading.Event()

    def run(self) -> None:
        i = 0
        while not self.stop.is_set():
            txn = wm_txn_t()
            txn.header = header_t()
            txn.client_id, txn.request_id, txn.expected_version = "fault-writer", i + 1, -1
            txn.ops = [op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube", f"w{i}"))]
            txn.num_ops = 1
            while True:
                try:
                    rep = self.rpc.call("commit", txn, wm_commit_t, timeout=5.0, retry_interval=0.01)
                    break
                except RpcTimeout:
                    continue  # the same transaction again: the server answers it once
                except (RpcRemoteError, RpcError) as e:  # refused, or an answer that does not decode
                    with self.cond:
                        self.refused.append(f"w{i}: {e}")
                        self.cond.notify_all()
                    return
            with self.cond:
                self.acked.append(rep.version)
                self.cond.notify_all()
            i += 1

    def count(self) -> int:
        with self.cond:
            return len(self.acked)

    def wait_for(self, n: int, timeout: float) -> bool:
        with self.cond:
            return self.cond.wait_for(lambda: len(self.acked) >= n or self.refused, timeout)


class Server:
    def __init__(self, work: Path, shim: str, snapshot_every: int, fsync_delay_us: int) -> None:
        self.work, self.data = work, work / "data"
        self.shadow, self.log = work / "shadow", work / "fsync.log"
        self.data.mkdir(parents=True, exist_ok=True)
        self.shadow.mkdir(exist_ok=True)
        self.env = dict(os.environ)
        if shim:
            self.env.update(LD_PRELOAD=shim, SB_FSYNC_DIR=str(self.data), SB_FSYNC_SHADOW=str(self.shadow),
                            SB_FSYNC_LOG=str(self.log), SB_FSYNC_DELAY_US=str(fsync_delay_us))
        self.argv = [str(paths.binary("wm_server")), "--wall-clock", "--data", str(self.data), "--name", "wm-faults",
                     "--snapshot-every", str(snapshot_every)]
        self.proc: subprocess.Popen | None = None
        self.lives = 0
        self.torn_cut = 0
        self.names_reverted = 0   # power losses that took back a name the directory had not synced
        self.unsynced_files = 0   # files with bytes written after their last sync at a power loss

    def start(self) -> int:
        """Starts the server; returns the version it recovered. A refusal to start ends the run."""
        self.lives += 1
        self.stderr = self.work / "wm.log"
        with open(self.stderr, "w") as err:
            self.proc = subprocess.Popen(self.argv, stdout=subprocess.DEVNULL, stderr=err, env=self.env)

        def started() -> bool:
            if STARTED.search(self.stderr.read_text()):
                return True
            if self.proc.poll() is not None:
                raise RuntimeError(f"wm_server did not start (exit code {self.proc.returncode}): "
                                   f"{self.stderr.read_text()[-2000:]}")
            return False

        wait_until(started, 30, "wm_server's start", interval=0.002)
        text = self.stderr.read_text()
        if "[warn] wm_journal: cut off a torn record" in text:
            self.torn_cut += 1
        return int(STARTED.search(text).group(1))

    def kill(self) -> None:
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(10)

    def stop(self) -> None:
        self.proc.terminate()
        self.proc.wait(10)

    def power_loss(self, mode: str, rng: random.Random) -> int:
        """Rebuilds the data directory as a power loss now could leave it; returns how many
        bytes written after the last sync it dropped."""
        sizes: dict[int, int] = {}
        names: dict[str, int] = {}
        for line in self.log.read_text().splitlines() if self.log.exists() else []:
            kind, *rest = line.split()
            if kind == "F":
                sizes[int(rest[0])] = int(rest[1])
            elif kind == "D":
                names = {n: int(i) for n, i in (p.rsplit(":", 1) for p in rest)}
        kept: dict[str, bytes] = {}
        dropped = 0
        live_names = {p.name: p.stat().st_ino for p in self.data.iterdir()}
        if any(live_names.get(n) != i for n, i in names.items()) or set(live_names) - set(names):
            self.names_reverted += 1  # a rename or creation not yet made durable by a directory sync
        for name, ino in names.items():
            src = self.shadow / str(ino)
            if not src.exists():  # never synced: empty on disk, unless some of it made it
                live = self.data / name
                src = live if live.exists() and live.stat().st_ino == ino else None
            content = src.read_bytes() if src else b""
            synced = sizes.get(ino, 0)
            durable, unsynced = content[:synced], content[synced:]
            extra = rng.randint(0, len(unsynced)) if unsynced and mode != "power-synced" else 0
            durable += unsynced[:extra] if mode == "power-prefix" else bytes(extra)
            dropped += len(unsynced) - extra
            if unsynced:
                self.unsynced_files += 1
            kept[name] = durable
        for p in self.data.iterdir():
            p.unlink()
        lines = []
        for name, content in kept.items():
            path = self.data / name
            with open(path, "wb") as f:
                f.write(content)
                f.flush()
                os.fsync(f.fileno())
            ino = path.stat().st_ino
            os.link(path, self.shadow / str(ino))  # what is on disk now is durable
            lines.append(f"F {ino} {len(content)}\n")
        fd = os.open(self.data, os.O_RDONLY)
        os.fsync(fd)
        os.close(fd)
        lines.append("D" + "".join(f" {n}:{(self.data / n).stat().st_ino}" for n in kept) + "\n")
        with open(self.log, "a") as f:
            f.writelines(lines)
        return dropped


def spin(seconds: float) -> None:
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        pass


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, required=True)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--work", type=Path, required=True)
    ap.add_argument("--shim", default="")
    ap.add_argument("--snapshot-every", type=int, default=7)
    ap.add_argument("--fsync-delay-us", type=int, default=300, help="the shim's slow disk: each sync takes this longer")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    server = Server(args.work, args.shim, args.snapshot_every, args.fsync_delay_us)
    failures: list[str] = []
    modes = collections.Counter()
    dropped_bytes = 0
    in_flight_durable = 0
    t0 = time.monotonic()
    version = server.start()
    writer = Writer()
    writer.start()
    for point in range(args.points):
        target = writer.count() + rng.choice((0, 0, 0, 1, 2, 4, 8, 12))  # often 0: right after a restart
        if not writer.wait_for(target, 30):
            failures.append(f"point {point}: no progress ({writer.count()} of {target} acknowledgements)")
            break
        if writer.refused:
            failures.append(f"point {point}: a commit was refused: {writer.refused[0]}")
            break
        spin(rng.uniform(0, 0.003))
        server.kill()
        time.sleep(0.003)  # an answer sent before the kill lands now
        acked = writer.count()
        mode = rng.choice(MODES) if args.shim else "kill"
        modes[mode] += 1
        if mode != "kill":
            dropped_bytes += server.power_loss(mode, rng)
        try:
            version = server.start()
        except Exception as e:  # noqa: BLE001 - the refusal is the finding
            keep = args.work / f"failed-point-{point}"
            shutil.copytree(server.data, keep)
            failures.append(f"point {point} ({mode}, {acked} acknowledged): {e}; the files: {keep}")
            break
        if not acked <= version <= acked + 1:
            failures.append(f"point {point} ({mode}): {acked} commits acknowledged, the server recovered "
                            f"version {version}")
            break
        in_flight_durable += version - acked
    writer.stop.set()
    writer.join(30)
    wrong = [(i, v) for i, v in enumerate(writer.acked) if v != i + 1]
    if wrong:
        failures.append(f"acknowledgements with the wrong version (w<i>: version): {wrong[:10]}")
    wmi = WorldModelInterface(open_bus(), "fault-reader", timeout=10.0)
    labels = collections.Counter(e.label for e in wmi.get_elements())
    acked_labels = [f"w{i}" for i in range(len(writer.acked))]
    survivors = sum(1 for w in acked_labels if labels[w] == 1)
    doubled = [w for w in acked_labels if labels[w] > 1]
    extra = sorted(set(labels) - set(acked_labels))
    if survivors != len(acked_labels) or doubled or extra:
        failures.append(f"the world: {survivors} of {len(acked_labels)} acknowledged labels once, doubled "
                        f"{doubled[:10]}, not acknowledged {extra[:10]}")
    server.stop()
    print(json.dumps({"ok": not failures, "points": args.points, "modes": dict(modes),
                      "acknowledged": len(writer.acked), "survivors": survivors, "version": wmi.version,
                      "in_flight_durable": in_flight_durable, "torn_tails_cut": server.torn_cut,
                      "unsynced_bytes_dropped": dropped_bytes, "unsynced_files": server.unsynced_files,
                      "names_reverted": server.names_reverted, "server_starts": server.lives,
                      "seconds": round(time.monotonic() - t0, 1), "failures": failures}), flush=True)
    return 0 if not failures else 1


if __name__ == "__main__":
    sys.exit(main())
