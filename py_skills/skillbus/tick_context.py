"""The tick a skill process is answering, for code that must know its frame.

Under lockstep a skill process answers the manager's ticks between its own frames; what a
primitive starts in a tick of frame n must take effect at a frame fixed by n, not by when
the tick happened to arrive (the CAN link holds CAN sends until frame n + 1, the gripper
driver shows the status of frame n - 1). The skill process sets the context around each
tick; outside a tick there is none.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Iterator


@dataclass(frozen=True)
class Tick:
    frame: int         # the manager's lockstep frame (-1 outside lockstep)
    sim_time_ns: int


_current: Tick | None = None


def current_tick() -> Tick | None:
    """The tick being answered under lockstep, else None."""
    return _current


@contextlib.contextmanager
def ticking(frame: int, sim_time_ns: int) -> Iterator[None]:
    global _current
    prev, _current = _current, (Tick(frame, sim_time_ns) if frame >= 0 else None)
    try:
        yield
    finally:
        _current = prev


def now_s() -> float:
    """A skill's "now" in seconds: the tick's sim time under lockstep, the monotonic clock
    otherwise (only differences of it mean anything)."""
    import time
    return _current.sim_time_ns * 1e-9 if _current is not None else time.monotonic()
