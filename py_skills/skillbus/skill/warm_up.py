"""Work a skill library starts when it loads, in a thread, finished before lockstep frames.

A library may have slow work that need not hold up loading (TaskPlan imports its planner:
about 2.5 s of CPU). Done in a thread, the process goes on registering meanwhile; but a
thread still running when the process joins a lockstep session takes a core, and the
interpreter's lock, from every frame: the pick-and-place demo ran at 11x real time with
the planner importing beside it and at 15x without (docs/benchmarks.md). So a skill
process under lockstep waits for its libraries' warm-ups (`wait`) before it joins; on the
wall clock it serves at once and the warm-up goes on beside it.

    from skillbus.skill import warm_up
    warm_up.in_background(import_my_planner, "planner-import")
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Callable

log = logging.getLogger("skillbus.skill")

_started: list[threading.Thread] = []


def in_background(fn: Callable[[], object], name: str) -> threading.Thread:
    """Runs fn() in a daemon thread named `name`. A failure is logged, never raised: the
    work is an optimisation, and the use it prepares (the first plan) reports it."""
    def run() -> None:
        try:
            fn()
        except Exception as e:
            log.warning("warm-up %s failed (%s: %s); what it prepares will say why when used", name,
                        type(e).__name__, e)
    t = threading.Thread(target=run, name=name, daemon=True)
    _started.append(t)
    t.start()
    return t


def running() -> list[str]:
    """The names of the warm-ups not finished."""
    return [t.name for t in _started if t.is_alive()]


def wait(timeout: float) -> list[str]:
    """Waits at most `timeout` seconds in all for every warm-up; returns the names of those
    still running then (the caller says so and goes on: they only cost time)."""
    deadline = time.monotonic() + timeout
    for t in list(_started):
        t.join(max(0.0, deadline - time.monotonic()))
    return running()
