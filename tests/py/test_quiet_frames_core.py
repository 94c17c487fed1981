"""skillbus_native.QuietFrames, the core that acks a Python participant's quiet frames,
against Python's own participant code: datagrams in LCM's wire format sent to it over a
loopback UDP socket (unicast: nothing leaves the machine), acks out to memq://."""

import hashlib
import socket

import pytest

import skillbus_native
from skillbus import auth, native, quiet_frames
from skillbus.bus import AuthenticatedBus, DropEveryNthBus, LcmBus
from skillbus.lockstep_wire import AckEncoder
from skillbus.msgs import channel_count_t, header_t, lockstep_clock_t
from skillbus.policy import Policy

CLOCK, ACK, NAME = "SB_LOCKSTEP_CLOCK", "SB_LOCKSTEP_ACK", "p1"
KEY = bytes(range(32))


def clock(frame, sim_time=None, master="clock", names=(NAME, "p2"), counts=(), stop=False) -> bytes:
    c = lockstep_clock_t()
    c.header = header_t()
    c.header.frame, c.header.sender, c.header.seq = frame, master, 0
    c.header.sim_time_ns = frame * 10_000_000 if sim_time is None else sim_time
    c.frame_period_ns = 10_000_000
    c.participants, c.num_participants = list(names), len(names)
    c.counts, c.num_counts = list(counts), len(counts)
    c.stop, c.stop_reason = stop, "done" if stop else ""
    return c.encode()


def count(sender, channel, frame, n=1):
    c = channel_count_t()
    c.sender, c.channel, c.frame, c.count = sender, channel, frame, n
    return c


def datagram(channel: str, payload: bytes) -> bytes:
    return b"LC02" + bytes(4) + channel.encode() + b"\0" + payload


class Rig:
    """A core on a loopback socket, and Python's participant state around it."""

    def __init__(self, keys=()):
        self.rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.rx.bind(("127.0.0.1", 0))
        self.rx.setblocking(False)
        self.tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        # The bus's opener, shared with the core (as skillbus.quiet_frames shares it).
        self.opener = skillbus_native.Opener(list(keys), None) if keys else None
        self.core = skillbus_native.QuietFrames(self.rx.fileno(), CLOCK, ACK, "memq://", NAME, self.opener,
                                                keys[0] if keys else None, b"tester")
        self.core.set_subscribed(["SB_HEARD"])
        self.sealer = auth.Sealer(KEY, "clock") if keys else None
        self.last_acked, self.sim_time, self.last_ack, self.running = 0, 0, b"ack0", bytes(32)

    def send(self, channel, payload):
        if self.sealer:
            payload = self.sealer.seal(channel, payload)
        self.tx.sendto(datagram(channel, payload), self.rx.getsockname())

    def wait(self, timeout=0.2, horizon=None):
        more = horizon or ()
        out = self.core.wait(timeout, "clock", self.last_acked, self.sim_time, self.last_ack, self.running, *more)
        d, sender, acked, self.last_acked, self.sim_time, self.last_ack, self.running, resends, self.handed = out
        return d, sender, acked, resends

    def close(self):
        self.rx.close()
        self.tx.close()


@pytest.fixture(params=["open", "signed"])
def rig(request):
    r = Rig(keys=[KEY] if request.param == "signed" else [])
    yield r
    r.close()


def python_running(running: bytes, frames: int) -> bytes:
    for _ in range(frames):
        running = hashlib.sha256(running + hashlib.sha256().digest()).digest()
    return running


def test_quiet_frames_are_acked_with_pythons_bytes_and_running_digest(rig):
    for f in (1, 2, 3):
        rig.send(CLOCK, clock(f, counts=[count("p2", "SB_OTHER", f - 1), count(NAME, "SB_HEARD", f - 1)]))
    acked = 0
    for _ in range(10):
        d, _, n, _ = rig.wait()
        assert d is None
        acked += n
        if acked == 3:
            break
    assert acked == 3 and rig.last_acked == 3 and rig.sim_time == 30_000_000
    assert rig.last_ack == AckEncoder(NAME).encode(3, 30_000_000, [], hashlib.sha256().digest(), "")
    assert rig.running == python_running(bytes(32), 3)


@pytest.mark.parametrize("why,payload", [
    ("a message for it", clock(1, counts=[count("p2", "SB_HEARD", 0)])),
    ("another master", clock(1, master="intruder")),
    ("not listed", clock(1, names=("p2",))),
    ("a stop", clock(1, stop=True)),
    ("a frame skipped", clock(2)),
    ("time running backwards", clock(1, sim_time=-1)),
    ("a negative count", clock(1, counts=[count("p2", "SB_OTHER", 0, -1)])),
    ("a count from the future", clock(1, counts=[count("p2", "SB_OTHER", 5)])),
    ("not a clock", b"\x00" * 40),
])
def test_a_clock_with_work_or_anything_odd_goes_to_python_untouched(rig, why, payload):
    rig.send(CLOCK, payload)
    d, sender, acked, _ = rig.wait()
    assert acked == 0 and rig.last_acked == 0, why
    assert d is not None, why
    assert d[:4] == b"LC02" and d[8:8 + len(CLOCK)] == CLOCK.encode() and sender[0] == "127.0.0.1"
    opened = auth.Opener([KEY]).open(CLOCK, d[9 + len(CLOCK):]).payload if rig.sealer else d[9 + len(CLOCK):]
    assert rig.core.counts().get("ok", 0) == 0  # (not the core's to verify: Python verifies it once)
    assert opened == payload, why


def test_other_channels_and_fragments_go_to_python_in_order(rig):
    rig.send("SB_HEARD", b"hello")
    rig.send(CLOCK, clock(1))
    d, _, acked, _ = rig.wait()
    assert acked == 0 and b"SB_HEARD\0" in d  # the clock behind it waits its turn
    d, _, acked, _ = rig.wait()
    assert d is None and acked == 1
    rig.tx.sendto(b"LC03" + bytes(16), rig.rx.getsockname())
    d, _, _, _ = rig.wait()
    assert d[:4] == b"LC03"


def test_a_resent_clock_is_answered_with_the_last_ack_and_an_old_one_left_to_python(rig):
    rig.send(CLOCK, clock(1))
    assert rig.wait()[2] == 1
    rig.send(CLOCK, clock(1))  # the master did not get it: resent
    rig.send(CLOCK, clock(0))  # older still: Python verifies it (and ignores it)
    d, _, acked, resends = rig.wait(0.1)
    assert acked == 0 and resends == 1 and rig.last_acked == 1
    assert d is not None and b"SB_LOCKSTEP_CLOCK\0" in d


def test_the_wait_ends_at_its_timeout(rig):
    import time
    t = time.monotonic()
    assert rig.wait(0.05) == (None, None, 0, 0)
    assert 0.04 <= time.monotonic() - t < 1.0


def test_forged_and_replayed_clocks_are_dropped_and_counted():
    r = Rig(keys=[KEY])
    try:
        r.tx.sendto(datagram(CLOCK, clock(1)), r.rx.getsockname())  # unsigned
        other = auth.Sealer(bytes(32), "clock")
        r.tx.sendto(datagram(CLOCK, other.seal(CLOCK, clock(1))), r.rx.getsockname())  # another key
        genuine = datagram(CLOCK, r.sealer.seal(CLOCK, clock(1)))
        r.tx.sendto(genuine, r.rx.getsockname())
        r.tx.sendto(genuine, r.rx.getsockname())  # replayed
        acked, to_python = 0, []
        for _ in range(5):
            d, _, n, _ = r.wait(0.1)
            if d is not None:
                to_python.append(d)
            acked += n
        assert acked == 1 and to_python == [datagram(CLOCK, clock(1))]
        # The unsigned one Python drops (it is not the core's to verify: see the next test).
        assert r.core.counts() == {"ok": 1, "bad_mac": 1, "replayed": 1}
    finally:
        r.close()


def test_what_python_verified_is_a_replay_to_the_core_and_the_reverse():
    r = Rig(keys=[KEY])
    try:
        seen_by_python = r.sealer.seal(CLOCK, clock(1))
        assert r.opener.open(CLOCK, seen_by_python)[0]  # Python's path took it (a frame with work)
        r.tx.sendto(datagram(CLOCK, seen_by_python), r.rx.getsockname())  # replayed, a quiet frame now
        d, _, acked, _ = r.wait(0.1)
        assert d is None and acked == 0 and r.core.counts() == {"ok": 0, "replayed": 1}
        acked_by_core = r.sealer.seal(CLOCK, clock(1))
        r.tx.sendto(datagram(CLOCK, acked_by_core), r.rx.getsockname())
        assert r.wait()[2] == 1
        ok, reason, _, _ = r.opener.open(CLOCK, acked_by_core)
        assert not ok and reason == "replayed"
        # An unsigned clock the core leaves to Python, which counts it.
        r.tx.sendto(datagram(CLOCK, clock(2)), r.rx.getsockname())
        d, _, acked, _ = r.wait()
        assert d is not None and acked == 0
    finally:
        r.close()


def test_a_flood_of_forged_clocks_does_not_hold_the_wait_past_its_timeout():
    import threading
    import time
    r = Rig(keys=[KEY])
    stop = threading.Event()
    forger = auth.Sealer(bytes(32), "clock")
    forged = datagram(CLOCK, forger.seal(CLOCK, clock(1)))  # a quiet frame's clock: the core verifies it

    def flood():
        while not stop.is_set():
            r.tx.sendto(forged, r.rx.getsockname())

    t = threading.Thread(target=flood)
    t.start()
    try:
        time.sleep(0.05)
        start = time.monotonic()
        assert r.wait(0.05)[:3] == (None, None, 0)
        assert time.monotonic() - start < 2.0  # (its 0.05 s, the flood's thread holding the GIL meanwhile)
        assert r.core.counts()["bad_mac"] > 0
    finally:
        stop.set()
        t.join(5)
        r.close()


def test_a_socket_error_is_an_oserror_not_a_timeout():
    r = Rig()
    r.rx.close()  # (the fd the core reads is gone)
    try:
        with pytest.raises(OSError):
            r.wait(0.05)
    finally:
        r.tx.close()


@pytest.mark.parametrize("size", [16, 32, 64, 65, 100, 200])
def test_cpp_verifies_what_python_signs_with_keys_of_any_length(size):
    # HMAC pads a key to SHA-256's 64-byte block, and hashes a longer one first: each
    # side computes that on its own (common/src/auth.cpp, Python's hmac).
    key = bytes((7 * i + size) % 256 for i in range(size))
    r = Rig(keys=[key])
    try:
        r.sealer = auth.Sealer(key, "clock")
        r.send(CLOCK, clock(1))
        assert r.wait()[2] == 1 and r.core.counts() == {"ok": 1}
        r.sealer = auth.Sealer(key[:-1] + bytes([key[-1] ^ 1]), "clock")  # one bit off
        r.send(CLOCK, clock(2))
        assert r.wait(0.05)[2] == 0 and r.core.counts() == {"ok": 1, "bad_mac": 1}
    finally:
        r.close()


def test_bad_arguments_are_refused():
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        with pytest.raises(RuntimeError, match="no socket"):
            skillbus_native.QuietFrames(-1, CLOCK, ACK, "memq://", NAME, None, None, b"")
        with pytest.raises(TypeError, match="a skillbus_native.Opener or None"):
            skillbus_native.QuietFrames(rx.fileno(), CLOCK, ACK, "memq://", NAME, "opener", KEY, b"x")
        core = skillbus_native.QuietFrames(rx.fileno(), CLOCK, ACK, "memq://", NAME, None, None, b"")
        with pytest.raises(RuntimeError, match="initialised once"):
            core.__init__(rx.fileno(), CLOCK, ACK, "memq://", NAME, None, None, b"")
    finally:
        rx.close()


@pytest.fixture
def socket_bus(monkeypatch):
    """A memq:// LcmBus that reports a socket of its own, as a udpm:// one read on the
    caller's thread does (a udpm:// bus would join a multicast group on this host)."""
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    monkeypatch.setattr(LcmBus, "lane0_socket", lambda self: rx.fileno())
    bus = LcmBus("memq://")
    bus._by_channel[CLOCK] = {1: lambda c, d: None}  # (the participant's clock subscription)
    yield bus
    rx.close()


def test_a_bus_read_on_the_callers_thread_gets_the_core_and_nothing_else(socket_bus, monkeypatch):
    assert quiet_frames.for_bus(socket_bus, NAME, CLOCK, ACK) is not None
    signed = AuthenticatedBus(socket_bus, [KEY], "tester", Policy.parse("* *\n"))
    assert quiet_frames.for_bus(signed, NAME, CLOCK, ACK) is not None
    # Not: a test's wrapping bus; a policy that forbids its acks (Python names why at the
    # first ack); a rule only Python can run; a second subscriber to the clock; switched off.
    assert quiet_frames.for_bus(DropEveryNthBus(socket_bus, 3), NAME, CLOCK, ACK) is None
    assert quiet_frames.for_bus(AuthenticatedBus(socket_bus, [KEY], "tester", Policy.parse("SB_* other\n")),
                                NAME, CLOCK, ACK) is None
    assert quiet_frames.for_bus(AuthenticatedBus(socket_bus, [KEY], "tester", lambda i, c: True),
                                NAME, CLOCK, ACK) is None
    socket_bus._by_channel[CLOCK][2] = lambda c, d: None
    assert quiet_frames.for_bus(socket_bus, NAME, CLOCK, ACK) is None
    del socket_bus._by_channel[CLOCK][2]
    monkeypatch.setenv(native.ENV, "0")
    assert quiet_frames.for_bus(socket_bus, NAME, CLOCK, ACK) is None


# -- latest-only channels ------------------------------------------------------------------

STATE = "SB_STATE"


def stamped(frame, seq=0, sender="sim", body=b"") -> bytes:
    """A lockstep message: a fingerprint, then its header_t (what peek_stamp reads)."""
    import io
    h = header_t()
    h.frame, h.sim_time_ns, h.sender, h.seq = frame, frame * 10_000_000, sender, seq
    buf = io.BytesIO()
    h._encode_one(buf)
    return bytes(8) + buf.getvalue() + body


def latest_rig(rig):
    rig.core.set_subscribed(["SB_HEARD", STATE])
    rig.core.set_latest_only([STATE])
    return rig


def test_a_frame_whose_messages_are_all_latest_only_is_acked_and_hands_back_the_newest(rig):
    latest_rig(rig)
    # Frame 1's clock announces two states of frame 0; frame 2's one of frame 1, which
    # comes after its clock.
    rig.send(STATE, stamped(0, 0, body=b"a"))
    rig.send(STATE, stamped(0, 1, body=b"b"))
    rig.send(CLOCK, clock(1, counts=[count("sim", STATE, 0, 2)]))
    rig.send(CLOCK, clock(2, counts=[count("sim", STATE, 1, 1)]))
    rig.send(STATE, stamped(1, 0, body=b"c"))
    acked, handed = 0, []
    for _ in range(10):
        d, _, n, _ = rig.wait()
        assert d is None
        acked += n
        handed += rig.handed
        if acked == 2:
            break
    assert acked == 2 and rig.last_acked == 2
    assert rig.last_ack == AckEncoder(NAME).encode(2, 20_000_000, [], hashlib.sha256().digest(), "")
    assert rig.running == python_running(bytes(32), 2)
    # Only the newest, once: what a handler that keeps the newest would end with.
    assert handed == [(0, STATE, stamped(1, 0, body=b"c"))]
    if rig.sealer:
        assert rig.core.verdicts() == {("ok", CLOCK): 2, ("ok", STATE): 3}


def test_a_frame_with_a_message_that_does_not_come_is_handed_to_python_with_its_clock(rig):
    latest_rig(rig)
    rig.send(STATE, stamped(0, 0, body=b"a"))
    rig.send(CLOCK, clock(1, counts=[count("sim", STATE, 0, 2)]))  # the second state is lost
    d, _, acked, _ = rig.wait(0.1)
    assert d is None and acked == 0 and rig.last_acked == 0
    # Python takes the frame: the clock and what came of its messages, verified (Python's
    # inbox then waits for the rest and names the loss).
    assert sorted(rig.handed) == [(1, CLOCK, clock(1, counts=[count("sim", STATE, 0, 2)])),
                                  (2, STATE, stamped(0, 0, body=b"a"))]
    assert rig.wait(0.05)[:3] == (None, None, 0) and rig.handed == []


def test_a_frame_past_the_horizon_goes_to_python_with_what_the_core_held_for_it(rig):
    latest_rig(rig)
    rig.send(STATE, stamped(0))
    rig.send(CLOCK, clock(1, counts=[count("sim", STATE, 0)]))
    d, _, acked, _ = rig.wait(horizon=(1, 2**63 - 1))
    assert d is None and acked == 1
    rig.send(STATE, stamped(1, body=b"x"))
    rig.send(CLOCK, clock(2, counts=[count("sim", STATE, 1)]))
    d, _, acked, _ = rig.wait(horizon=(1, 2**63 - 1))  # (frame 2 is past it)
    assert acked == 0 and d is not None and CLOCK.encode() in d
    assert (2, STATE, stamped(1, body=b"x")) in rig.handed
    # a sim-time horizon too
    rig.last_acked, rig.sim_time = 1, 10_000_000
    rig.send(CLOCK, clock(2))
    d, _, acked, _ = rig.wait(horizon=(100, 20_000_000))
    assert acked == 0 and d is not None


def test_a_message_for_python_while_a_frame_is_collected_hands_python_the_frame(rig):
    latest_rig(rig)
    rig.send(CLOCK, clock(1, counts=[count("sim", STATE, 0)]))
    rig.send("SB_HEARD", b"tick")  # (a skill process's tick, say) before the state
    d, _, acked, _ = rig.wait()
    assert acked == 0 and b"SB_HEARD\0" in d
    assert [h[0] for h in rig.handed] == [1]  # its clock: Python collects the state itself


def test_own_stale_duplicate_and_unstamped_latest_messages(rig):
    latest_rig(rig)
    rig.last_acked = 5
    rig.send(STATE, stamped(3))           # older than the floor: stale
    rig.send(STATE, stamped(5, sender=NAME))  # its own: ignored
    rig.send(STATE, stamped(5))
    rig.send(STATE, stamped(5))           # the same (sender, frame, seq) again: a duplicate
    rig.send(STATE, b"no stamp at all")   # Python's to record: handed back, the frame Python's
    d, _, acked, _ = rig.wait()
    assert d is None and acked == 0
    assert (2, STATE, b"no stamp at all") in rig.handed and (2, STATE, stamped(5)) in rig.handed
    assert rig.core.latest_stats() == {"stale": 1, "duplicates": 1}


def test_forged_latest_messages_are_dropped_counted_and_do_not_complete_a_frame():
    r = latest_rig(Rig(keys=[KEY]))
    try:
        other = auth.Sealer(bytes(32), "sim")
        r.tx.sendto(datagram(STATE, other.seal(STATE, stamped(0))), r.rx.getsockname())  # another key
        r.tx.sendto(datagram(STATE, stamped(0)), r.rx.getsockname())  # unsigned
        r.send(CLOCK, clock(1, counts=[count("sim", STATE, 0)]))
        d, _, acked, _ = r.wait(0.1)
        assert acked == 0 and [h[0] for h in r.handed] == [1]  # not completed: Python's, by timeout
        verdicts = r.core.verdicts()
        assert verdicts[("bad_mac", STATE)] == 1 and verdicts[("unsigned", STATE)] == 1
        r.last_acked = 0
        r.send(STATE, stamped(0, body=b"genuine"))
        r.send(CLOCK, clock(1, counts=[count("sim", STATE, 0)]))
        for _ in range(5):
            if r.wait(0.1)[2]:
                break
        assert r.last_acked == 1 and r.handed == [(0, STATE, stamped(0, body=b"genuine"))]
    finally:
        r.close()


def test_held_messages_go_back_on_release_and_python_held_ones_complete_a_frame(rig):
    latest_rig(rig)
    rig.core.hold(STATE, stamped(0, body=b"from the inbox"), 0)  # what Python's inbox held
    rig.send(CLOCK, clock(1, counts=[count("sim", STATE, 0)]))
    assert rig.wait()[2] == 1
    assert rig.handed == [(0, STATE, stamped(0, body=b"from the inbox"))]
    rig.core.hold(STATE, stamped(1, body=b"next"), 1)
    assert rig.core.release() == [(2, STATE, stamped(1, body=b"next"))]
    assert rig.core.release() == []
    with pytest.raises(TypeError):
        rig.core.hold(STATE, "not bytes", 0)


def test_a_latest_only_channel_someone_else_hears_too_is_not_the_cores(socket_bus):
    socket_bus._by_channel[STATE] = {5: lambda c, d: None}
    q = quiet_frames.for_bus(socket_bus, NAME, CLOCK, ACK)
    q.set_subscribed({STATE}, {STATE})
    assert q.usable()
    socket_bus._by_channel[STATE][6] = lambda c, d: None  # a second subscriber, later
    assert not q.usable()  # (the core would take its datagrams)
    q.set_subscribed({STATE}, {STATE})
    assert q.usable() and q._latest == []  # then Python keeps that channel
