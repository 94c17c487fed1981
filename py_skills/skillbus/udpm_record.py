"""``skillbus record FILE`` on an LCM bus: every message of udpm:// (both lanes) into an
LCM event log, as lcm-logger writes one, without losing any under load.

lcm-logger receives on LCM's thread and queues what it has not yet handled, 30 messages
per subscription; a lockstep run at full speed publishes thousands a second, and when
the logger's process waited for a core for a few milliseconds (a busy 2-core machine)
the queue overflowed: a frame's state went missing now and then, and a replay of the run
said its log lacked messages. This recorder reads the sockets itself (skillbus.udpm) with
a 4 MB kernel receive buffer each (thousands of messages: seconds of a run) and writes
every message as it comes (skillbus.dds_record.LogWriter, the format of lcm-logger: read
by skillbus replay, the console, lcm-logplayer; flushed every 100 ms, so
skillbus.monitor.mark_log sees its marker). On dds:// ``skillbus record`` is
skillbus.dds_record.
"""

from __future__ import annotations

import math
import select
import time
from typing import Callable

from skillbus.bus import BusError, check_multicast_interface, lane1_url, udpm_address
from skillbus.dds_record import LogWriter
from skillbus.record import SPIN_MAX
from skillbus.udpm import UdpmReceiver

RECEIVE_BUFFER = 4 * 1024 * 1024


class UdpmRecorder:
    """Records every message of the udpm:// bus `url` (and its second lane) into `path`."""

    def __init__(self, url: str, path: str) -> None:
        check_multicast_interface(url)  # it joins the group: on this host only, unless told otherwise
        lanes = [udpm_address(lane) for lane in [url] + ([lane1_url(url)] if lane1_url(url) else [])]
        self.channels: set[str] = set()
        self.receivers = []
        self.log: LogWriter | None = None
        try:
            for group, port, _ in lanes:
                self.receivers.append(UdpmReceiver(group, port, RECEIVE_BUFFER))
        except OSError as e:
            self.close()
            raise BusError(f"cannot receive on {url}: {e.strerror} (for udpm:// the host needs a multicast route, "
                           f"e.g. `ip route add 224.0.0.0/4 dev lo`)") from None
        try:  # (once it can record: a bus it cannot join leaves an existing file as it was)
            self.log = LogWriter(path)
        except OSError:
            self.close()
            raise

    def spin(self, timeout: float = 0.05) -> int:
        """Writes what arrived, SPIN_MAX datagrams of each lane at most (a flooded lane does
        not starve the other), waiting at most `timeout` for it; returns the datagrams
        read."""
        ready, _, _ = select.select(self.receivers, [], [], timeout)
        read = 0
        for r in ready:
            for _ in range(SPIN_MAX):
                got = r.read()
                if got is False:  # (nothing more now; None: a fragment, or a datagram that does not parse)
                    break
                read += 1
                if got is not None:
                    self.log.write(got[0], got[1])
                    self.channels.add(got[0])
        self.log.flush_if_due()
        return read

    def drain(self, until: float = math.inf, abort: Callable[[], bool] = lambda: False) -> bool:
        """Writes what is in the sockets' buffers, without waiting for more: True once they
        are empty; False when they were not by `until` (time.monotonic()) or `abort()` (a
        bus sending faster than it writes)."""
        try:
            while self.spin(0.0):
                if time.monotonic() >= until or abort():
                    return not select.select(self.receivers, [], [], 0)[0]  # (they may have just run dry)
            return True
        finally:
            self.log.flush()

    def close(self) -> None:
        if self.log is not None:
            self.log.close()
        for r in self.receivers:
            r.close()
