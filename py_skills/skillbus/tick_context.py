"""The tick a skill process is answering, for code that must know its frame.

Under lockstep a skill process answers the manager's ticks between its own frames; what a
primitive starts in a tick of frame n must take effect at a frame fixed by n, not by when
the tick happened to arrive (the CAN link holds CAN sends until frame n + 1, the gripper
driver shows the status of frame n - 1). The skill process sets the context around each
tick; outside a tick there is none.
"""

from __future__ import annotations

from typing import NamedTuple


class Tick(NamedTuple):
    """(A tuple: every tick makes one, and a frozen dataclass cost a microsecond of it.)"""
    frame: int         # the manager's lockstep frame (-1 outside lockstep)
    sim_time_ns: int


_current: Tick | None = None


def current_tick() -> Tick | None:
    """The tick being answered under lockstep, else None."""
    return _current


class ticking:
    """``with ticking(frame, sim_time_ns):`` the tick being answered (none for a frame
    below 0: outside lockstep), the one before it again afterwards. A class rather than a
    generator-based context manager: every tick enters one."""

    __slots__ = ("_tick", "_prev")

    def __init__(self, frame: int, sim_time_ns: int) -> None:
        self._tick = Tick(frame, sim_time_ns) if frame >= 0 else None

    def __enter__(self) -> None:
        global _current
        self._prev, _current = _current, self._tick

    def __exit__(self, *exc: object) -> None:
        global _current
        _current = self._prev


def now_s() -> float:
    """A skill's "now" in seconds: the tick's sim time under lockstep, the monotonic clock
    otherwise (only differences of it mean anything)."""
    import time
    return _current.sim_time_ns * 1e-9 if _current is not None else time.monotonic()
