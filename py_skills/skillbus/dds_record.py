"""``skillbus dds-record FILE``: an LCM log of a Cyclone DDS domain, as lcm-logger writes
one of an LCM bus (docs/transport.md, "DDS").

Every skillbus topic on the domain (a writer of ``skillbus::Envelope``) is found through
DDS discovery (the built-in DCPSPublication topic) and read like any channel; each
message goes into the file as an LCM log event: the channel, the wall time it arrived,
and the bytes as they were on the wire (authenticators included, as lcm-logger keeps
them). The file is an LCM event log, so ``skillbus replay``, ``lcm-logplayer`` and the
tests read it as they read a log of LCM. It is flushed every 100 ms, so a reader (such as
``skillbus.monitor.mark_log``) sees what was recorded soon after.

A topic found late is read from its discovery on: what its writer kept for late readers
(the last 16 samples, no older than 2 s: skillbus.dds) is recorded too, on every channel
(a reader of state otherwise takes nothing written before it subscribed), so the first
messages of a channel are not lost while discovery runs.
"""

from __future__ import annotations

import logging
import math
import struct
import sys
import time
from pathlib import Path
from typing import Callable

from skillbus.bus import BusError
from skillbus.record import SPIN_MAX

ENVELOPE_TYPE = "skillbus::Envelope"
_SYNC = 0xEDA1DA01
_HEADER = struct.Struct(">IqqII")  # sync, event number, utime, channel length, data length
log = logging.getLogger("dds-record")
FLUSH_S = 0.1
DISCOVER_S = 0.005  # (a new topic is read at once: its first messages beyond the last 16 would be lost)


class LogWriter:
    """An LCM event log, written event by event."""

    def __init__(self, path: str | Path) -> None:
        self._f = open(path, "wb")
        self.events = 0
        self._last_flush = time.monotonic()

    def write(self, channel: str, data: bytes, utime: int | None = None) -> None:
        ch = channel.encode()
        utime = time.time_ns() // 1000 if utime is None else utime
        self._f.write(_HEADER.pack(_SYNC, self.events, utime, len(ch), len(data)) + ch + data)
        self.events += 1

    def flush_if_due(self) -> None:
        if time.monotonic() - self._last_flush >= FLUSH_S:
            self.flush()

    def flush(self) -> None:
        self._f.flush()
        self._last_flush = time.monotonic()

    def close(self) -> None:
        self._f.close()


class DdsRecorder:
    """Records every skillbus topic of the domain that `url` names into `path`."""

    def __init__(self, url: str, path: str | Path) -> None:
        from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication

        from skillbus.dds import DdsBus
        self.bus = DdsBus(url)  # (no key: the bytes are recorded as they came, authenticators and all)
        try:  # (once it can record: a domain it cannot join leaves an existing file as it was)
            self.log = LogWriter(path)
        except BaseException:
            self.bus.close()
            raise
        self.channels: set[str] = set()
        self.skipped: dict[str, str] = {}  # topics found that cannot be recorded, and why
        self._publications = BuiltinDataReader(self.bus._dp, BuiltinTopicDcpsPublication)
        self._next_discovery = 0.0

    def discover(self) -> None:
        """Subscribes to every skillbus topic a writer appeared on since the last call."""
        while True:
            found = self._publications.take(N=64)
            for p in found:
                name = getattr(p, "topic_name", None)
                if getattr(p, "type_name", None) == ENVELOPE_TYPE and name and name not in self.channels:
                    self.channels.add(name)
                    try:
                        self.bus.subscribe(name, self.log.write, history=True)
                    except BusError as e:  # (a topic no skillbus channel can be: a writer of another build)
                        self.skipped[name] = str(e)
                        log.warning("not recording DDS topic %s: %s", ascii(name), e)
            if len(found) < 64:
                return

    def drain(self, until: float = math.inf, abort: Callable[[], bool] = lambda: False) -> bool:
        """Writes what has reached the recorder, without waiting for more: True once its
        queues are empty; False when they were not by `until` (time.monotonic()) or
        `abort()` (a bus sending faster than it writes)."""
        self.discover()
        try:
            while self.bus.handle(0.0):
                if time.monotonic() >= until or abort():
                    return not self.bus.handle(0.0)  # (they may have just run dry)
            return True
        finally:
            self.log.flush()

    def spin(self, timeout: float = DISCOVER_S) -> int:
        """Writes what arrived, SPIN_MAX messages at most, waiting at most `timeout` for
        one when none was waiting; returns how many it wrote."""
        now = time.monotonic()
        if now >= self._next_discovery:
            self.discover()
            self._next_discovery = now + DISCOVER_S
        n = 0
        while n < SPIN_MAX and self.bus.handle(0.0):
            n += 1
        if n == 0 and self.bus.handle(timeout):
            n = 1
        self.log.flush_if_due()
        return n

    def close(self) -> None:
        self.log.close()
        self.bus.close()


def main(args) -> int:
    """``skillbus dds-record``: ``skillbus record`` for DDS domains only."""
    from skillbus import record
    from skillbus.bus import resolve_url
    url = resolve_url(args.url)
    if not url.startswith("dds://"):
        print(f"error: dds-record records a DDS domain; the bus is {url} (skillbus record records either)", file=sys.stderr)
        return 2
    return record.main(args)
