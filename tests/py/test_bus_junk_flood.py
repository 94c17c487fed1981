"""A flood of datagrams that dispatch nothing (malformed, fragments never completed,
channels nobody here reads) does not hold a bus's handle() past its timeout: the direct
reader looks at the time every JUNK_CHECK of them (skillbus.bus.LcmBus._handle_direct).
The receivers are stand-ins that never run dry; the quiet-frame core's own flood test is
tests/py/test_quiet_frames_core.py."""

from __future__ import annotations

import socket
import threading
import time

import pytest

from skillbus import bus as bus_mod


class Junk:
    """A receiver with a datagram always waiting, one that completes no message (None) or
    one for a channel nobody subscribed to."""

    def __init__(self, what) -> None:
        self.what = what
        self.sock, self._peer = socket.socketpair()
        self.reads = 0

    def read(self):
        self.reads += 1
        return self.what


@pytest.mark.parametrize("what", [None, ("SB_NOBODY_READS", b"x")], ids=["malformed", "unsubscribed"])
def test_handle_returns_at_its_timeout_under_a_flood_of_junk(what):
    b = bus_mod.LcmBus.__new__(bus_mod.LcmBus)
    junk = Junk(what)
    b._read_orders = (([junk], [junk.sock]), ([junk], [junk.sock]))
    b._turn, b._by_channel, b._caught_up = 0, {}, 0.0
    out = {}
    t0 = time.monotonic()
    th = threading.Thread(target=lambda: out.setdefault("r", b._handle_direct(0.05)), daemon=True)
    th.start()
    th.join(20)
    assert not th.is_alive(), "handle(0.05) still reading junk after 20 s"
    assert out["r"] is False and time.monotonic() - t0 < 5
    assert junk.reads >= bus_mod.JUNK_CHECK


@pytest.mark.parametrize("at", [2, 256, 257, 1000])
def test_a_message_after_junk_is_delivered_once_by_handle_0(at):
    """handle(0.0) looks at the time at the 256th datagram that dispatched nothing and gives
    up there: a wanted message read then or after is still delivered, once."""
    got = []

    class Then(Junk):
        def read(self):
            self.reads += 1
            if self.reads < at:
                return None
            return ("SB_WANTED", b"m") if self.reads == at else False

    b = bus_mod.LcmBus.__new__(bus_mod.LcmBus)
    r = Then(None)
    b._read_orders = (([r], [r.sock]), ([r], [r.sock]))
    b._turn, b._caught_up = 0, 0.0
    b._by_channel = {"SB_WANTED": {1: lambda ch, d: got.append(d)}}
    calls = [b._handle_direct(0.0) for _ in range(10)]
    assert got == [b"m"] and calls.count(True) == 1, (got, calls)


def test_junk_then_a_quiet_socket_waits_only_what_is_left_of_the_timeout():
    """A first pass of junk that takes most of the timeout is not followed by a whole
    timeout's wait."""
    class SlowJunk(Junk):
        def read(self):
            self.reads += 1
            if self.reads <= 2 * bus_mod.JUNK_CHECK - 1:
                time.sleep(0.001)  # (about 0.5 s of junk in all)
                return None
            return False

    b = bus_mod.LcmBus.__new__(bus_mod.LcmBus)
    r = SlowJunk(None)
    b._read_orders = (([r], [r.sock]), ([r], [r.sock]))
    b._turn, b._by_channel, b._caught_up = 0, {}, 0.0
    t0 = time.monotonic()
    assert b._handle_direct(0.6) is False
    assert time.monotonic() - t0 < 0.6 + 0.3
