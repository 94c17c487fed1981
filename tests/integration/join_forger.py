"""Forges lockstep joins inside a test's sandbox (test_lockstep_processes.py).

    join_forger.py unsigned NAMES PID SECONDS    every 5 ms a join for each of NAMES from
                                                 process PID, without a trailer
    join_forger.py wrong-key NAMES PID SECONDS   the same, signed with a key of its own

A join under a participant's name from another process tells the master that participant
was started again, which ends the session (docs/lockstep.md). Runs for SECONDS, then
prints one JSON line: {"sent": N}.
"""

from __future__ import annotations

import json
import shutil
import sys
import tempfile
import time
from pathlib import Path

from skillbus import auth
from skillbus.bus import channel, open_raw_bus
from skillbus.msgs import lockstep_join_t


def join(name: str, pid: int) -> bytes:
    j = lockstep_join_t()
    j.participant, j.kind, j.pid = name, "forger", pid
    return j.encode()


def main() -> int:
    mode, names, pid, seconds = sys.argv[1], sys.argv[2].split(","), int(sys.argv[3]), float(sys.argv[4])
    bus = open_raw_bus()
    ch = channel("SB_LOCKSTEP_JOIN")
    sealer = None
    if mode == "wrong-key":
        keys = Path(tempfile.mkdtemp())
        sealer = auth.Sealer(auth.load_keys(auth.create_key_file(keys / "other.key"))[0], names[0])
        shutil.rmtree(keys)
    sent = 0
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        for n in names:
            data = join(n, pid)
            bus.publish(ch, sealer.seal(ch, data) if sealer else data)
            sent += 1
        time.sleep(0.005)
    print(json.dumps({"sent": sent}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
