"""Run a short block to its end even if Ctrl-C (SIGINT) or SIGTERM arrives inside it.

Why: writing one episode is several steps (its parquet file renamed into place, its
line in episodes.jsonl, its stats line, info.json). A KeyboardInterrupt between two of
them would leave a file without its meta line or a stray ``.tmp``. The signal is held
until the block ends and then raised as KeyboardInterrupt, so the dataset is always
whole episodes only. Only the main thread receives signals in Python; elsewhere the
block just runs. (Blocking the signals with pthread_sigmask, as skillbus.launch does
while it shuts down, is not enough here: generate's worker threads do not block them, the
kernel hands the signal to one of them, and Python still raises it in the main thread.)
Blocks nest: the outermost one holds the signal, so a caller can make
"write the episode and count it" one step.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

HELD = (signal.SIGINT, signal.SIGTERM)
_depth = 0  # blocks open on the main thread


@contextmanager
def uninterrupted() -> Iterator[None]:
    global _depth
    if threading.current_thread() is not threading.main_thread() or _depth:
        yield
        return
    arrived: list[int] = []
    previous = {s: signal.signal(s, lambda signum, _frame: arrived.append(signum)) for s in HELD}
    _depth += 1
    try:
        yield
    finally:
        _depth -= 1
        for s, handler in previous.items():
            signal.signal(s, handler)
    if arrived:
        raise KeyboardInterrupt(f"signal {arrived[0]} arrived while an episode was being written; it was finished")
