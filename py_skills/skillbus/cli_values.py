"""Argument types for the command line: a number an option cannot mean is refused by
argparse, naming the option (exit 2), instead of reaching the command.

Seen before: ``--timeout nan`` ended in a traceback (``cannot convert float NaN to
integer``) or meant "never"; ``--timeout -1`` was taken ("no server answered within -1
s"); ``record --seconds -5`` returned at once with an empty log and exit 0; ``--node-id 0``
ended in canopen's TypeError; ``lockstep-session --frames -5`` never ended.

>>> seconds("2.5"), seconds_or_never("0"), node_id("127"), count("0")
(2.5, 0.0, 127, 0)
>>> seconds("nan")
Traceback (most recent call last):
    ...
argparse.ArgumentTypeError: 'nan' is not a number of seconds greater than 0
>>> node_id("0")
Traceback (most recent call last):
    ...
argparse.ArgumentTypeError: '0' is not a CANopen node id (1 to 127)
"""

from __future__ import annotations

import argparse
import math


def _number(text: str) -> float | None:
    try:
        v = float(text)
    except ValueError:
        return None
    return v if math.isfinite(v) else None


def seconds(text: str) -> float:
    """A duration: finite, greater than 0."""
    v = _number(text)
    if v is None or v <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds greater than 0")
    return v


def seconds_or_never(text: str) -> float:
    """A duration, or 0 for none (run's and watch's --timeout)."""
    v = _number(text)
    if v is None or v < 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of seconds (0: never)")
    return v


def positive(text: str) -> float:
    """A finite number greater than 0 (a speed, a period)."""
    v = _number(text)
    if v is None or v <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number greater than 0")
    return v


def non_negative(text: str) -> float:
    """A finite number, 0 or more (a width)."""
    v = _number(text)
    if v is None or v < 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of 0 or more")
    return v


def count(text: str) -> int:
    """A whole number, 0 or more."""
    try:
        v = int(text)
    except ValueError:
        v = -1
    if v < 0:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of 0 or more")
    return v


def node_id(text: str) -> int:
    """A CANopen node id: 1 to 127."""
    try:
        v = int(text)
    except ValueError:
        v = 0
    if not 1 <= v <= 127:
        raise argparse.ArgumentTypeError(f"{text!r} is not a CANopen node id (1 to 127)")
    return v
