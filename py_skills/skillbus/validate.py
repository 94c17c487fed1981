"""Checks of received values: every number a Python process takes from the bus or a CAN
frame and acts on goes through one of these first (docs/transport.md, "Untrusted input").

A message that decodes is not yet a message to act on: LCM carries any double, NaN and
infinities included, and any integer of its width; a CAN frame carries whatever bytes a
node put in it. One such value used as it came has killed a process (a forged physics
state with ``finger_width=inf`` made the gripper device raise OverflowError turning it
into micrometres) or made it act on nonsense (a negative width, a target beyond the
fingers' travel). So a receiver checks each value it uses, before it uses any of them:

* the check functions return the value (as the type the receiver wants) or raise
  :class:`BadValue`, which names the field, its value (as ``repr``, so control
  characters and odd floats are shown escaped) and the rule it broke;
* the receiver then drops the whole message or frame (one bad field means the sender or
  the wire is broken: its other fields are not trusted either), keeps what it had, and
  records the reject in a :class:`Rejects` counter, which logs the first of each kind once
  and counts all of them for the process's summary.

    try:
        width = finite(s.finger_width, "finger_width", lo=0.0, hi=0.085)
    except BadValue as e:
        rejects.record(m.channel, e)
        return

Bounds are the physical or protocol limits of what the value means (a width between
closed and fully open, a time that does not run backwards), with a margin where a
measurement may overshoot a little; they are not the limits of a double.
"""

from __future__ import annotations

import logging
import math
import re
from collections import Counter
from typing import Any, Iterable, Sequence

REPR_LIMIT = 80  # characters of a rejected value shown in a log line (a forged string may be huge)
MAX_KINDS = 64   # kinds one Rejects tells apart; further ones are counted together
_INDEX = re.compile(r"\[\d+\]")


def shown(value: Any) -> str:
    """The value as a log line shows it: repr (escaped), cut to REPR_LIMIT characters."""
    text = repr(value)
    return text if len(text) <= REPR_LIMIT else text[:REPR_LIMIT - 3] + "..."


class BadValue(ValueError):
    """A received value that is not acted on: `name` is the field, `value` what came,
    `why` the rule it broke. str() reads "finger_width=inf: not a finite number"."""

    def __init__(self, name: str, value: Any, why: str) -> None:
        self.name, self.value, self.why = name, value, why
        super().__init__(f"{name}={shown(value)}: {why}")


def finite(value: Any, name: str, lo: float | None = None, hi: float | None = None) -> float:
    """`value` as a float, if it is a finite number within [lo, hi] (either bound may be
    None). NaN fails every comparison, so it is tested first: a NaN would pass a range
    check written as ``not (v < lo)``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise BadValue(name, value, "not a number")
    try:
        v = float(value)
    except OverflowError:  # an int too large for a double
        raise BadValue(name, value, "not a finite number") from None
    if not math.isfinite(v):
        raise BadValue(name, value, "not a finite number")
    _in_range(v, value, name, lo, hi)
    return v


def integer(value: Any, name: str, lo: int | None = None, hi: int | None = None) -> int:
    """`value` if it is an int (not a bool, not a float) within [lo, hi]."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise BadValue(name, value, "not an integer")
    _in_range(value, value, name, lo, hi)
    return value


def _in_range(v: float | int, value: Any, name: str, lo: float | None, hi: float | None) -> None:
    if lo is not None and v < lo:
        raise BadValue(name, value, f"below {lo:g}")
    if hi is not None and v > hi:
        raise BadValue(name, value, f"above {hi:g}")


def finite_all(values: Iterable[Any], name: str, lo: float | None = None, hi: float | None = None,
               length: int | None = None) -> list[float]:
    """Every value finite and within [lo, hi], and (if given) exactly `length` of them.
    A bad element is named with its index: ``position[2]``."""
    # The common case at a frame's rate (a state's joints, a list or tuple): every value a
    # float, finite, within the bounds, checked without naming each one; anything else is
    # checked one by one (an iterator lazily), which names the first bad value as ever.
    if (isinstance(values, (list, tuple)) and all(type(v) is float for v in values)
            and all(map(math.isfinite, values))
            and (not values or ((lo is None or min(values) >= lo) and (hi is None or max(values) <= hi)))):
        out = list(values)
    else:
        out = [finite(v, f"{name}[{i}]", lo, hi) for i, v in enumerate(values)]
    if length is not None and len(out) != length:
        raise BadValue(name, f"{len(out)} values", f"{length} expected")
    return out


def one_of(value: Any, name: str, allowed: Iterable[Any]) -> Any:
    """`value` if it is one of `allowed` (codes, enumerations)."""
    allowed = tuple(allowed)
    if value not in allowed:
        raise BadValue(name, value, f"not one of {', '.join(shown(a) for a in allowed)}")
    return value


def text(value: Any, name: str, nonempty: bool = True) -> str:
    """`value` if it is a str (non-empty unless nonempty=False)."""
    if not isinstance(value, str):
        raise BadValue(name, value, "not a string")
    if nonempty and not value:
        raise BadValue(name, value, "empty")
    return value


QUATERNION_TOLERANCE = 1e-2  # |norm - 1|: drivers normalise; a forged or zeroed quaternion is far off


def pose(values: Sequence[Any], name: str, reach: float) -> list[float]:
    """A pose x y z qx qy qz qw: seven finite numbers, the position within `reach` metres
    of the origin on each axis, the rotation a unit quaternion (within
    QUATERNION_TOLERANCE): a zero or huge quaternion is no rotation, and every transform
    made from it would be garbage."""
    v = finite_all(values, name, length=7)
    if not all(-reach <= x <= reach for x in v[:3]):  # (named axis by axis only when one is out)
        for i, axis in enumerate("xyz"):
            finite(v[i], f"{name}.{axis}", -reach, reach)
    norm = math.sqrt(sum(q * q for q in v[3:]))
    if abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise BadValue(f"{name}.rotation", v[3:], f"not a unit quaternion (norm {norm:.6g})")
    return v


def kind_of(where: str, field: str) -> str:
    """The kind a reject is counted as: where it came from and the field, without indices
    ("SB_ROBOT_OBJECTS: objects[].pose[]"), so that one bad array is one kind."""
    return f"{where}: {_INDEX.sub('[]', field)}"


class Rejects:
    """What one receiver dropped, counted per kind (kind_of: "<where>: <field>", e.g.
    "SB_ROBOT_ARM_STATE: tool_pose.rotation"). The first reject of each kind is logged
    (one warning line, the value escaped); the rest are only counted, so a flood of forged
    messages cannot flood the log. Fields may carry names from the message (a property's
    key), so after MAX_KINDS kinds the others are counted as one more per source,
    "<where>: other kinds": neither memory nor the log grows with what a forger makes up. `total` and `by_kind`
    go into the process's summary."""

    def __init__(self, component: str) -> None:
        self.log = logging.getLogger(component)
        self.by_kind: Counter[str] = Counter()

    def record(self, where: str, error: BadValue | str) -> None:
        """Counts one dropped message or frame from `where` (a channel, a CAN object);
        `error` is the BadValue that dropped it, or the reason as fixed text."""
        kind = kind_of(where, error.name if isinstance(error, BadValue) else str(error))
        if kind not in self.by_kind and len(self.by_kind) >= MAX_KINDS:
            kind = f"{where}: other kinds"
        self.by_kind[kind] += 1
        if self.by_kind[kind] == 1:
            self.log.warning("rejected %s: %s -- dropped, nothing acted on; further rejects of this kind are "
                             "counted, not logged", where, error)

    @property
    def total(self) -> int:
        return sum(self.by_kind.values())

    def summary(self) -> dict[str, int]:
        """Counts by kind, for a JSON summary."""
        return dict(sorted(self.by_kind.items()))
