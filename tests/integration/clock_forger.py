"""Forges lockstep clocks inside a test's sandbox (test_quiet_frames.py).

    clock_forger.py unsigned MASTER NAMES SECONDS   for every genuine clock heard, clocks
                                                    for its frame and the next, listing
                                                    NAMES, from MASTER, without a trailer
    clock_forger.py wrong-key MASTER NAMES SECONDS  the same, signed with a key of its own
    clock_forger.py replay MASTER NAMES SECONDS     every genuine clock heard, sent again
                                                    as it was on the wire

Each runs for SECONDS, then prints one JSON line: {"sent": N}.
"""

from __future__ import annotations

import collections
import json
import sys
import tempfile
import time
from pathlib import Path

from skillbus import auth
from skillbus.bus import channel, open_raw_bus
from skillbus.lockstep_wire import decode_clock
from skillbus.msgs import header_t, lockstep_clock_t


def clock(master: str, names: list[str], frame: int) -> bytes:
    c = lockstep_clock_t()
    c.header = header_t()
    c.header.frame, c.header.sim_time_ns, c.header.sender, c.header.seq = frame, frame * 10_000_000, master, 0
    c.frame_period_ns = 10_000_000
    c.participants, c.num_participants = names, len(names)
    c.counts, c.num_counts = [], 0
    c.stop, c.stop_reason = False, ""
    return c.encode()


def main() -> int:
    mode, master, names, seconds = sys.argv[1], sys.argv[2], sys.argv[3].split(","), float(sys.argv[4])
    bus = open_raw_bus()
    ch = channel("SB_LOCKSTEP_CLOCK")
    sent = 0
    end = time.monotonic() + seconds
    if mode == "replay":
        heard: list[bytes] = []
        bus.subscribe(ch, lambda _c, data: heard.append(bytes(data)))
        while time.monotonic() < end:
            bus.handle(0.01)
            for data in heard:  # (what this forger sends it hears too: once each)
                bus.publish(ch, data)
                sent += 1
            heard.clear()
            bus.handle(0.01)
            heard.clear()
    else:
        # A watcher of the bus: for every genuine clock heard, a forged one for the same
        # frame (what a resend would be) and for the next (what the next clock would be).
        sealer = None
        if mode == "wrong-key":
            path = auth.create_key_file(Path(tempfile.mkdtemp()) / "other.key")
            sealer = auth.Sealer(auth.load_keys(path)[0], master)
        frames: list[int] = []
        mine: collections.Counter[bytes] = collections.Counter()  # (what it sent comes back to it)

        def heard(_c: str, data: bytes) -> None:
            if mine[bytes(data)] > 0:
                mine[bytes(data)] -= 1
                return
            try:
                frames.append(decode_clock(auth.strip(data)).header.frame)
            except ValueError:
                pass  # (a forged one of its own, cut by strip)

        bus.subscribe(ch, heard)
        while time.monotonic() < end:
            bus.handle(0.01)
            for f in frames:
                for forged in (f, f + 1):
                    data = clock(master, names, forged)
                    data = sealer.seal(ch, data) if sealer else data
                    mine[data] += 1
                    bus.publish(ch, data)
                    sent += 1
            frames.clear()
    print(json.dumps({"sent": sent}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
