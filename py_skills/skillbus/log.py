"""Logging set-up and a counter for bad input that cannot flood the log."""

from __future__ import annotations

import logging
import os
import sys
from collections import Counter


def setup_logging(level: str | None = None) -> None:
    level = (level or os.environ.get("SKILLBUS_LOG_LEVEL", "info")).upper()
    logging.basicConfig(stream=sys.stderr, level=getattr(logging, level, logging.INFO),
                        format="[%(levelname)s] %(name)s: %(message)s")
    if level != "DEBUG":  # the canopen library narrates every PDO it reads at INFO: only its warnings
        logging.getLogger("canopen").setLevel(logging.WARNING)


class BadInputCounter:
    """Counts bad messages per channel; logs the first five of a channel, then every 1000th."""

    def __init__(self, component: str) -> None:
        self.log = logging.getLogger(component)
        self.by_channel: Counter[str] = Counter()

    def record(self, channel: str, why: str, size: int) -> None:
        self.by_channel[channel] += 1
        n = self.by_channel[channel]
        if n <= 5 or n % 1000 == 0:
            self.log.warning("bad message #%d on %s (%d bytes): %s -- dropped", n, channel, size, why)

    @property
    def total(self) -> int:
        return sum(self.by_channel.values())
