"""A long-running process's objects from its start, set aside from Python's cyclic garbage
collector once it is ready to serve.

Everything a process builds before it serves (modules, skill libraries, the ontology,
a world-model replica: about 120,000 objects in the demo's skill process) lives as long
as the process. Python's full collection walks every tracked object each time it runs, so
its pause grows with that start-up heap: 18-26 ms in the demo's skill process, at a moment
no one chooses (a tick, a frame). `gc.freeze` moves them to a generation the collector
never walks; what the process allocates afterwards is collected as before. Nothing is
freed late: what was reachable at start-up is in use for the process's life.
"""

from __future__ import annotations

import gc


def set_aside() -> int:
    """Collects once, then freezes what is left; returns how many objects were set aside
    (the collector's permanent generation). Idempotent: a second call adds what came
    since."""
    gc.collect()
    gc.freeze()
    return gc.get_freeze_count()


def release() -> int:
    """Gives the set-aside objects back to the collector (its oldest generation), before a
    process drops a large part of its start-up heap; returns how many there were."""
    n = gc.get_freeze_count()
    if n:
        gc.unfreeze()
    return n
