"""Argument types for the command line: a number an option cannot mean is refused by
argparse, naming the option (exit 2), instead of reaching the command.

Seen before: ``--timeout nan`` ended in a traceback (``cannot convert float NaN to
integer``) or meant "never"; ``--timeout -1`` was taken ("no server answered within -1
s"); ``record --seconds -5`` returned at once with an empty log and exit 0; ``--node-id 0``
ended in canopen's TypeError; ``lockstep-session --frames -5`` never ended.

>>> seconds("2.5"), seconds_or_never("0"), node_id("127"), count("0"), port("0")
(2.5, 0.0, 127, 0, 0)
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
from typing import Any, Callable


def _finite(text: str) -> float:
    v = float(text)
    if not math.isfinite(v):
        raise ValueError(text)
    return v


def _checked(parse: Callable[[str], Any], fits: Callable[[Any], bool], what: str) -> Callable[[str], Any]:
    """An argparse type: `parse(text)` when it parses and `fits`, else an error naming
    `what` the option takes (argparse names the option and exits 2)."""
    def check(text: str) -> Any:
        try:
            v = parse(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None
        if not fits(v):
            raise argparse.ArgumentTypeError(f"{text!r} is not {what}")
        return v
    return check


seconds = _checked(_finite, lambda v: v > 0, "a number of seconds greater than 0")  # a duration
seconds_or_never = _checked(_finite, lambda v: v >= 0, "a number of seconds (0: never)")  # run's, watch's --timeout
positive = _checked(_finite, lambda v: v > 0, "a number greater than 0")  # a speed, a period
non_negative = _checked(_finite, lambda v: v >= 0, "a number of 0 or more")  # a width
count = _checked(int, lambda v: v >= 0, "a whole number of 0 or more")
at_least_one = _checked(int, lambda v: v >= 1, "a whole number of 1 or more")
node_id = _checked(int, lambda v: 1 <= v <= 127, "a CANopen node id (1 to 127)")
port = _checked(int, lambda v: 0 <= v <= 65535, "a TCP port (0 to 65535; 0: any free port)")
