"""The console's bus thread under a flood (a bus that never runs dry): the web page's jobs
still run and the thread still stops, since it dispatches DISPATCH_MAX messages at most
between two looks at them (skillbus.console.bus_worker)."""

from __future__ import annotations

from skillbus.console import bus_worker
from skillbus.console.bus_worker import BusWorker


class EndlessBus:
    def __init__(self) -> None:
        self.handled = 0

    def handle(self, timeout: float) -> bool:
        self.handled += 1
        return True

    def caught_up_at(self) -> float:
        return 0.0


class JunkBus(EndlessBus):
    """A bus flooded with datagrams nobody reads: each handle() gives up on them (False)
    without having caught up."""

    def handle(self, timeout: float) -> bool:
        self.handled += 1
        return False


def test_jobs_chores_and_the_stop_get_through_a_flood():
    bus = EndlessBus()
    w = BusWorker(lambda: bus, poll_s=0.05)
    chores = []
    w.every(0.01, lambda: chores.append(1))
    w.start()
    try:
        assert w.submit(lambda: "served").result(timeout=10) == "served"
        assert w.submit(lambda: len(chores)).result(timeout=10) >= 1
        assert bus.handled >= bus_worker.DISPATCH_MAX  # (the flood was dispatched meanwhile)
    finally:
        w.stop(timeout=10)
    assert not w._thread.is_alive()


def test_a_bus_that_gives_up_on_junk_is_read_again_at_once():
    """(Not after the poll period: the wanted messages behind the junk would wait, and a
    socket flooded meanwhile overflows.)"""
    import time
    bus = JunkBus()
    w = BusWorker(lambda: bus, poll_s=0.5)
    w.start()
    try:
        time.sleep(0.5)
        assert bus.handled > 20, bus.handled  # (about 1 with a wait of poll_s after each)
        assert w.submit(lambda: "served").result(timeout=10) == "served"
    finally:
        w.stop(timeout=10)
    assert not w._thread.is_alive()
