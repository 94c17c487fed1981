"""One thread that owns the console's bus.

The bus, its subscriptions and RPC clients are not thread-safe: every use of them runs
on this thread. The web server's handlers submit jobs (:meth:`BusWorker.submit`) and
await their results; between jobs the thread dispatches what arrives
(``bus.handle``) and runs the periodic chores. A job that raises passes its exception
to the waiting handler; a subscriber that raises is logged and the thread goes on.
"""

from __future__ import annotations

import concurrent.futures
import logging
import queue
import threading
import time
from typing import Any, Callable

log = logging.getLogger("skillbus.console")
# The most messages dispatched between two looks at the jobs, the chores and the stop: a
# bus that sends faster than the console reads must not starve the web page's requests.
DISPATCH_MAX = 1000


class BusWorker:
    def __init__(self, open_bus: Callable[[], Any], poll_s: float = 0.05) -> None:
        self._open_bus = open_bus
        self._poll_s = poll_s
        self._wake = threading.Event()
        self._jobs: queue.SimpleQueue = queue.SimpleQueue()
        self._chores: list[tuple[float, Callable[[], None], list[float]]] = []
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._main, name="console-bus", daemon=True)
        self.bus: Any = None
        self.error: BaseException | None = None

    def start(self, timeout: float = 10.0) -> None:
        self._thread.start()
        if not self._ready.wait(timeout):
            raise RuntimeError(f"the console's bus did not open within {timeout} s")
        if self.error is not None:
            raise RuntimeError(f"the console's bus did not open: {self.error}") from self.error

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        self._wake.set()
        self._thread.join(timeout)

    def every(self, period_s: float, chore: Callable[[], None]) -> None:
        """Runs `chore` on the bus thread about every `period_s` (first: at once)."""
        self._chores.append((period_s, chore, [0.0]))

    def submit(self, fn: Callable[[], Any]) -> concurrent.futures.Future:
        """Runs `fn()` on the bus thread; its result (or exception) in the future."""
        fut: concurrent.futures.Future = concurrent.futures.Future()
        self._jobs.put((fn, fut))
        self._wake.set()
        return fut

    def on_thread(self) -> bool:
        return threading.current_thread() is self._thread

    def _main(self) -> None:
        try:
            self.bus = self._open_bus()
        except BaseException as e:  # (said by start())
            self.error = e
            self._ready.set()
            return
        self._ready.set()
        # The bus is read in batches, every poll_s (or at once when a job comes): what
        # arrived meanwhile waits in the socket's receive buffer. A watcher woken by each
        # datagram of a busy lockstep bus (thousands a second) would take the cores from
        # the participants that many times, for nothing it needs at once.
        while not self._stop.is_set():
            self._run_jobs()
            self._run_chores()
            try:
                batch_began = time.monotonic()
                for _ in range(DISPATCH_MAX):
                    if not self.bus.handle(0.0):
                        break
                else:  # (more waiting: the jobs and the stop first, then at once the rest)
                    continue
                if self.bus.caught_up_at() < batch_began:
                    continue  # (a handle() that gave up on a flood of junk: the rest at once too)
            except Exception:
                log.exception("the bus failed while dispatching")
            self._wake.wait(self._poll_s)
            self._wake.clear()
        self._run_jobs(cancel=True)

    def _run_jobs(self, cancel: bool = False) -> None:
        while True:
            try:
                fn, fut = self._jobs.get_nowait()
            except queue.Empty:
                return
            if cancel:
                fut.cancel()
                continue
            if not fut.set_running_or_notify_cancel():
                continue
            try:
                fut.set_result(fn())
            except BaseException as e:
                fut.set_exception(e)

    def _run_chores(self) -> None:
        now = time.monotonic()
        for period, chore, last in self._chores:
            if now - last[0] >= period:
                last[0] = now
                try:
                    chore()
                except Exception:
                    log.exception("console chore %s failed", getattr(chore, "__name__", chore))
