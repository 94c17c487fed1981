"""Logging set-up and a counter for bad input that cannot flood the log."""

from __future__ import annotations

import logging
import os
import sys
from collections import Counter


MAX_LINE = 2000
_CONTROL = {c: f"\\x{c:02x}" for c in list(range(0x20)) + [0x7f]}
_CONTROL[ord("\\")] = "\\\\"


def log_safe(text: str, max_chars: int = MAX_LINE) -> str:
    """`text` as one printable line: control characters and backslashes escaped, cut after
    `max_chars` with a note of how much was left out (log text often quotes what came over
    the wire: a newline in it would forge log lines, a terminal escape would hide them).

    >>> log_safe("forged\\n[INFO] all well\\x1b[2K")
    'forged\\\\x0a[INFO] all well\\\\x1b[2K'
    >>> log_safe("x" * 10, 4)
    'xxxx... (6 more characters)'
    """
    cut = text[:max_chars]
    out = cut.translate(_CONTROL)
    return out if len(text) <= max_chars else f"{out}... ({len(text) - max_chars} more characters)"


class SafeFormatter(logging.Formatter):
    """One line per record, escaped and bounded (log_safe); a traceback stays readable
    below it (it is ours, not the wire's)."""

    def format(self, record: logging.LogRecord) -> str:
        text = log_safe(record.getMessage())
        line = f"[{record.levelname}] {record.name}: {text}"
        if record.exc_info:
            line += "\n" + self.formatException(record.exc_info)
        return line


LEVELS = ("DEBUG", "INFO", "WARN", "WARNING", "ERROR")


def setup_logging(level: str | None = None) -> None:
    if level is None:
        level = os.environ.get("SKILLBUS_LOG_LEVEL", "info")
        if level.strip().upper() not in LEVELS:  # (said, as the C++ programs say it: not a silent info)
            print(f"warning: $SKILLBUS_LOG_LEVEL {level!r} is not debug, info, warn or error: logging at info",
                  file=sys.stderr)
            level = "info"
    level = level.strip().upper()
    if level == "WARN":
        level = "WARNING"
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(SafeFormatter())
    logging.basicConfig(level=getattr(logging, level, logging.INFO), handlers=[handler])
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
