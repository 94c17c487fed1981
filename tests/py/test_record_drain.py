"""A recorder under a flood still stops: each spin writes SPIN_MAX messages at most (so the
recording loop looks at its stop), and a stop writes what keeps coming for DRAIN_S at most
(or until a second signal), then says the log ends there. The buses here are stand-ins
that never run dry; the real processes are tests/integration/test_record_flood.py."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import threading
import time

import can
import pytest

from skillbus import dds_record, record, udpm_record
from skillbus.can import canlog
from skillbus.dds_record import LogWriter
from skillbus.record import SPIN_MAX

LIMIT_S = 20  # a recorder that never stops fails the test instead of hanging it


def finishes(fn, *args, **kwargs):
    """fn(*args) in a thread; its result, or a failure if it has not returned in LIMIT_S."""
    out: dict = {}
    t = threading.Thread(target=lambda: out.setdefault("r", fn(*args, **kwargs)), daemon=True)
    t.start()
    t.join(LIMIT_S)
    assert not t.is_alive(), f"{fn.__name__} did not return within {LIMIT_S} s under a flood"
    return out.get("r")


class EndlessSocket:
    """A receiver whose socket is always readable and which always has a datagram."""

    def __init__(self, readable: bool = True) -> None:
        self.a, self.b = socket.socketpair()
        if readable:
            self.b.send(b"x")  # (readable for select, for ever: never read)
        self.reads = 0

    def fileno(self) -> int:
        return self.a.fileno()

    def read(self):
        self.reads += 1
        return ("SB_FLOOD", b"m")

    def close(self) -> None:
        self.a.close()
        self.b.close()


@pytest.fixture
def flooded_udpm(tmp_path):
    rec = udpm_record.UdpmRecorder.__new__(udpm_record.UdpmRecorder)
    rec.channels, rec.receivers = set(), [EndlessSocket()]
    rec.log = LogWriter(tmp_path / "flood.lcmlog")
    yield rec
    rec.close()


class EndlessDdsBus:
    """A DdsBus with a sample always waiting: each handle() gives one to the subscriber."""

    def __init__(self, deliver) -> None:
        self.deliver = deliver

    def handle(self, timeout: float) -> bool:
        self.deliver("SB_FLOOD", b"m")
        return True

    def close(self) -> None:
        pass


@pytest.fixture
def flooded_dds(tmp_path):
    rec = dds_record.DdsRecorder.__new__(dds_record.DdsRecorder)
    rec.channels, rec.skipped = set(), {}
    rec.log = LogWriter(tmp_path / "flood.lcmlog")
    rec.bus = EndlessDdsBus(rec.log.write)
    rec._next_discovery = float("inf")
    rec.discover = lambda: None
    yield rec
    rec.close()


@pytest.mark.parametrize("kind", ["udpm", "dds"])
def test_a_spin_under_a_flood_returns_after_spin_max(kind, request):
    rec = request.getfixturevalue(f"flooded_{kind}")
    assert finishes(rec.spin, 0.0) == SPIN_MAX


@pytest.mark.parametrize("kind", ["udpm", "dds"])
def test_a_stop_under_a_flood_ends_after_the_drain_time_and_says_so(kind, request, capsys):
    rec = request.getfixturevalue(f"flooded_{kind}")
    calls = []

    def stopped() -> bool:  # (the stop comes at the third look, in the middle of the flood)
        calls.append(1)
        return len(calls) >= 3

    t0 = time.monotonic()
    events = finishes(record.record_until, rec, stopped, drain_s=0.3)
    took = time.monotonic() - t0
    assert 0.3 <= took < 0.3 + 5, took
    assert events > 2 * SPIN_MAX  # (what the spins before the stop and the drain wrote)
    assert "still coming when it stopped writing, 0.3 s after the stop" in capsys.readouterr().err


def test_a_flooded_lane_does_not_starve_the_other(tmp_path):
    class Some(EndlessSocket):
        def __init__(self) -> None:
            super().__init__()
            self.left = 5

        def read(self):
            self.reads += 1
            if not self.left:
                return False
            self.left -= 1
            return ("SB_LOCKSTEP_ACK", b"a")

    flooded, acks = EndlessSocket(), Some()
    rec = udpm_record.UdpmRecorder.__new__(udpm_record.UdpmRecorder)
    rec.channels, rec.receivers = set(), [flooded, acks]  # (lane 0 flooded, lane 1 with 5 acks)
    rec.log = LogWriter(tmp_path / "two.lcmlog")
    try:
        assert finishes(rec.spin, 0.0) == SPIN_MAX + 5
        assert flooded.reads == SPIN_MAX and acks.left == 0
    finally:
        rec.close()


def test_a_drain_whose_time_ends_as_the_queues_run_dry_says_nothing(tmp_path, capsys):
    """(The last messages written right at the drain's end: nothing was left, no warning.)"""
    class LastOnesSlow(EndlessSocket):
        def __init__(self) -> None:
            super().__init__()
            self.left = 3

        def read(self):
            if not self.left:
                return False
            self.left -= 1
            time.sleep(0.2)
            if not self.left:
                self.a.recv(1)  # (select: nothing waiting once the last is read)
            return ("SB_LAST", b"m")

    rec = udpm_record.UdpmRecorder.__new__(udpm_record.UdpmRecorder)
    rec.channels, rec.receivers = set(), [LastOnesSlow()]
    rec.log = LogWriter(tmp_path / "last.lcmlog")
    assert record.record_until(rec, lambda: True, drain_s=0.3) == 3
    assert capsys.readouterr().err == ""


def test_a_second_signal_ends_the_drain_at_once(flooded_udpm):
    t0 = time.monotonic()
    finishes(record.record_until, flooded_udpm, lambda: True, drain_s=60, abort=lambda: time.monotonic() - t0 > 0.2)
    assert time.monotonic() - t0 < 10


def test_a_drain_that_empties_the_queues_writes_everything_and_says_nothing(tmp_path, capsys):
    """(The stop as it was: what reached the recorder is written; no warning.)"""
    class Some(EndlessSocket):
        def __init__(self, n: int) -> None:
            super().__init__()
            self.left = n

        def read(self):
            if not self.left:
                return False
            self.left -= 1
            return ("SB_SOME", b"m")

    rec = udpm_record.UdpmRecorder.__new__(udpm_record.UdpmRecorder)
    rec.channels, rec.receivers = set(), [Some(2500)]
    rec.log = LogWriter(tmp_path / "some.lcmlog")
    assert record.record_until(rec, lambda: True, drain_s=30) == 2500
    assert capsys.readouterr().err == ""


@contextlib.contextmanager
def signal_after(delay_s: float, sig: int):
    """`sig` to this process after `delay_s`; the handlers of SIGTERM and SIGINT (which the
    recorders replace) as they were afterwards."""
    old = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGINT)}
    timer = threading.Timer(delay_s, os.kill, (os.getpid(), sig))
    try:
        timer.start()
        yield
    finally:
        timer.cancel()
        for s, h in old.items():
            signal.signal(s, h)


class EndlessCanBus:
    """can.Bus as can-record opens it, with a frame always waiting."""

    def __init__(self, *args, **kwargs) -> None:
        self.frame = can.Message(arbitration_id=0x185, data=b"\x00" * 8, is_extended_id=False)

    def recv(self, timeout=None):
        return self.frame

    def shutdown(self) -> None:
        pass


def test_can_record_under_a_flood_stops_after_the_drain_time(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(canlog.can, "Bus", EndlessCanBus)
    monkeypatch.setattr(canlog, "DRAIN_S", 0.3)
    with signal_after(0.2, signal.SIGTERM):
        t0 = time.monotonic()
        n = canlog.record("flood", str(tmp_path / "flood.log"), seconds=LIMIT_S)
        took = time.monotonic() - t0
    assert took < 5, f"can-record took {took:.1f} s to stop under a flood"
    assert n > 0 and "still coming when it stopped writing, 0.3 s after the stop" in capsys.readouterr().err


def test_a_signal_during_the_drain_after_seconds_ends_it(tmp_path, monkeypatch, flooded_udpm):
    """`skillbus record --seconds S`: the recording ends by its time, and the first Ctrl-C
    during its drain ends that (before, only a second one did)."""
    import argparse
    monkeypatch.setattr(record, "open_recorder", lambda url, path: flooded_udpm)
    monkeypatch.setattr(record, "DRAIN_S", 60.0)
    with signal_after(0.6, signal.SIGINT):
        t0 = time.monotonic()
        rc = record.main(argparse.Namespace(file=str(tmp_path / "x.lcmlog"), url="udpm://239.255.76.67:7667", seconds=0.2))
        took = time.monotonic() - t0
    assert rc == 0 and took < 10, took


def test_can_record_a_signal_during_the_drain_after_seconds_ends_it(tmp_path, monkeypatch):
    monkeypatch.setattr(canlog.can, "Bus", EndlessCanBus)
    monkeypatch.setattr(canlog, "DRAIN_S", 60.0)
    with signal_after(0.6, signal.SIGTERM):
        t0 = time.monotonic()
        n = canlog.record("flood", str(tmp_path / "flood.log"), seconds=0.2)
        took = time.monotonic() - t0
    assert n > 0 and took < 10, took
