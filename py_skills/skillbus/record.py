"""``skillbus record FILE``: every message of the bus into an LCM event log, the format
lcm-logger writes, losing none under load (docs/transport.md, "Recording"). The recorder
is skillbus.udpm_record's on LCM and skillbus.dds_record's on DDS; this runs either until
SIGINT, SIGTERM or --seconds, then prints what it wrote as JSON.
"""

from __future__ import annotations

import signal
import sys
import time
from typing import Callable

from skillbus.bus import BusError, resolve_url

# How long a stop goes on writing what reached the recorder before it. A bus that keeps
# sending faster than the recorder writes would keep it from ever ending; a signal that
# comes meanwhile ends it at once. (A full 4 MB socket buffer of small messages takes
# about 0.1 s.)
DRAIN_S = 2.0
# The most messages one spin() of a recorder writes before it returns, so that its caller
# looks at its stop: a bus that sends faster than it writes must not keep it from stopping.
SPIN_MAX = 1000


def say_drain_cut(program: str, what: str, drain_s: float) -> None:
    """On stderr: the recorder stopped writing while `what` (messages, frames) still came."""
    print(f"{program}: {what} were still coming when it stopped writing, {drain_s:g} s after the stop "
          "(or at a signal meanwhile): the log ends there", file=sys.stderr, flush=True)


def open_recorder(url: str, path: str):
    """The recorder of the bus `url`, writing `path`; BusError for a bus it cannot record
    (or join), OSError for a file it cannot write."""
    if url.startswith("dds://"):
        from skillbus.dds_record import DdsRecorder
        return DdsRecorder(url, path)
    if url.startswith("udpm://"):
        from skillbus.udpm_record import UdpmRecorder
        return UdpmRecorder(url, path)
    raise BusError(f"record reads udpm:// and dds:// buses; the bus is {url}")


def main(args) -> int:
    """`args`: file, url (None: $SKILLBUS_BUS_URL), seconds (None: until a signal)."""
    stop: list[int] = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda s, f: stop.append(s))
    try:
        rec = open_recorder(resolve_url(args.url), args.file)
    except OSError as e:
        print(f"error: cannot write {args.file}: {e.strerror}", file=sys.stderr)
        return 2
    except BusError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print("recording", file=sys.stderr, flush=True)
    deadline = time.monotonic() + args.seconds if args.seconds is not None else None
    signals_at_stop: list[int] = []  # how many signals had come when the recording stopped

    def stopped() -> bool:
        if stop or (deadline is not None and time.monotonic() >= deadline):
            signals_at_stop[:] = signals_at_stop or [len(stop)]
            return True
        return False

    # A signal during the drain (a second Ctrl-C, or the first after --seconds) ends it.
    events = record_until(rec, stopped, abort=lambda: len(stop) > signals_at_stop[0])
    print(f'{{"events": {events}, "channels": {len(rec.channels)}}}', flush=True)
    return 0


def record_until(rec, stopped: Callable[[], bool], drain_s: float | None = None,
                 abort: Callable[[], bool] = lambda: False) -> int:
    """Runs the recorder `rec` until `stopped()`, then writes what had reached it by then
    and closes it; returns the events written. A stop (SIGTERM) can come while messages
    wait in the recorder's queues: on DDS their writers already have the recorder's
    acknowledgement and will not send them again, so leaving them unread would lose them.
    Messages that keep coming after the stop are written for `drain_s` at most (default
    DRAIN_S) or until `abort()`; the log then ends, and stderr says so."""
    drain_s = DRAIN_S if drain_s is None else drain_s
    try:
        while not stopped():
            rec.spin()
        if not rec.drain(time.monotonic() + drain_s, abort):
            say_drain_cut("record", "messages", drain_s)
    finally:
        events = rec.log.events
        rec.close()
    return events
