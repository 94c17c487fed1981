"""The part of rospy that skills use for time and logging, for SkiROS2 skills that import
rospy only for that: ``import rospy`` becomes
``from skillbus.skill import ros_clock as rospy``.

Time is a skill's "now" (skillbus.tick_context.now_s): the tick's sim time under
lockstep, the monotonic clock otherwise, so only differences of times mean anything
(``(rospy.Time.now() - start).to_sec()``), as in the skills that measure a wait.

    >>> (Time(3, 500_000_000) - Time(1)).to_sec()
    2.5
    >>> (Time(1) + Duration(0.25)).to_sec()
    1.25
"""

from __future__ import annotations

import functools
import logging

from skillbus import tick_context

_log = logging.getLogger("skillbus.skill.rospy")


@functools.total_ordering
class Duration:
    def __init__(self, secs: float = 0, nsecs: int = 0) -> None:
        self._s = float(secs) + nsecs * 1e-9

    def to_sec(self) -> float:
        return self._s

    def to_nsec(self) -> int:
        return round(self._s * 1e9)

    def __add__(self, other: "Duration") -> "Duration":
        return Duration(self._s + other.to_sec())

    def __sub__(self, other: "Duration") -> "Duration":
        return Duration(self._s - other.to_sec())

    def __neg__(self) -> "Duration":
        return Duration(-self._s)

    def __mul__(self, k: float) -> "Duration":
        return Duration(self._s * k)

    __rmul__ = __mul__

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Duration) and self._s == other._s

    def __lt__(self, other: "Duration") -> bool:
        return self._s < other.to_sec()

    def __hash__(self) -> int:
        return hash(self._s)

    def __repr__(self) -> str:
        return f"Duration({self._s})"


@functools.total_ordering
class Time:
    def __init__(self, secs: float = 0, nsecs: int = 0) -> None:
        self._s = float(secs) + nsecs * 1e-9

    @classmethod
    def now(cls) -> "Time":
        return cls(tick_context.now_s())

    def to_sec(self) -> float:
        return self._s

    def to_nsec(self) -> int:
        return round(self._s * 1e9)

    def __sub__(self, other: "Time | Duration") -> "Duration | Time":
        if isinstance(other, Time):
            return Duration(self._s - other._s)
        return Time(self._s - other.to_sec())

    def __add__(self, other: Duration) -> "Time":
        return Time(self._s + other.to_sec())

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Time) and self._s == other._s

    def __lt__(self, other: "Time") -> bool:
        return self._s < other._s

    def __hash__(self) -> int:
        return hash(self._s)

    def __repr__(self) -> str:
        return f"Time({self._s})"


def get_time() -> float:
    return tick_context.now_s()


def loginfo(msg: object, *args: object) -> None:
    _log.info(str(msg), *args)


def logwarn(msg: object, *args: object) -> None:
    _log.warning(str(msg), *args)


def logerr(msg: object, *args: object) -> None:
    _log.error(str(msg), *args)


def logdebug(msg: object, *args: object) -> None:
    _log.debug(str(msg), *args)
