"""An episode's recorder: every message of an LCM bus (udpm://, both lanes) into an LCM
event log, as lcm-logger writes one, without losing any under load.

lcm-logger receives on LCM's thread and queues what it has not yet handled, 30 messages
per subscription; a lockstep run at full speed publishes thousands a second, and when
the logger's process waited for a core for a few milliseconds (two episodes on two
cores) the queue overflowed: a frame's state went missing now and then, and the episode
had to be run again. This recorder reads the sockets itself (skillbus.udpm) with a
4 MB kernel receive buffer each (thousands of messages: seconds of a run) and writes
every message as it comes (skillbus.dds_record.LogWriter: flushed every 100 ms, so
skillbus.monitor.mark_log sees its marker).

    python -m skillbus.generate.recorder FILE      # the bus of $SKILLBUS_BUS_URL; until SIGTERM or SIGINT
"""

from __future__ import annotations

import os
import select
import signal
import sys

from skillbus.bus import lane1_url, udpm_address
from skillbus.dds_record import LogWriter
from skillbus.udpm import UdpmReceiver

RECEIVE_BUFFER = 4 * 1024 * 1024


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python -m skillbus.generate.recorder FILE", file=sys.stderr)
        return 2
    url = os.environ.get("SKILLBUS_BUS_URL", "udpm://")
    if not url.startswith("udpm://"):
        print(f"error: the recorder reads udpm:// buses; the bus is {url}", file=sys.stderr)
        return 2
    lanes = [url] + ([lane1_url(url)] if lane1_url(url) else [])
    receivers = []
    for lane in lanes:
        group, port, _ = udpm_address(lane)
        receivers.append(UdpmReceiver(group, port, RECEIVE_BUFFER))
    out = LogWriter(argv[0])
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    print("recording", file=sys.stderr, flush=True)
    try:
        while not stop:
            ready, _, _ = select.select(receivers, [], [], 0.05)
            for r in ready:
                while True:
                    got = r.read()
                    if got is False:
                        break
                    if got is not None:
                        out.write(got[0], got[1])
            out.flush_if_due()
    finally:
        out.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
