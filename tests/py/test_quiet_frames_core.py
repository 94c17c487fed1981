"""skillbus_native.QuietFrames, the core that acks a Python participant's quiet frames,
against Python's own participant code: datagrams in LCM's wire format sent to it over a
loopback UDP socket (unicast: nothing leaves the machine), acks out to memq://."""

import hashlib
import socket

import pytest

import skillbus_native
from skillbus import auth, quiet_frames
from skillbus.bus import DropEveryNthBus, LcmBus
from skillbus.lockstep_wire import AckEncoder
from skillbus.msgs import channel_count_t, header_t, lockstep_clock_t

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

    def __init__(self, keys=(), policy=""):
        self.rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.rx.bind(("127.0.0.1", 0))
        self.rx.setblocking(False)
        self.tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.core = skillbus_native.QuietFrames(self.rx.fileno(), CLOCK, ACK, "memq://", NAME, list(keys),
                                                "tester", policy)
        self.core.set_subscribed(["SB_HEARD"])
        self.sealer = auth.Sealer(KEY, "clock") if keys else None
        self.last_acked, self.sim_time, self.last_ack, self.running = 0, 0, b"ack0", bytes(32)

    def send(self, channel, payload):
        if self.sealer:
            payload = self.sealer.seal(channel, payload)
        self.tx.sendto(datagram(channel, payload), self.rx.getsockname())

    def wait(self, timeout=0.2):
        out = self.core.wait(timeout, "clock", self.last_acked, self.sim_time, self.last_ack, self.running)
        d, sender, acked, self.last_acked, self.sim_time, self.last_ack, self.running, resends = out
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


def test_a_resent_clock_is_answered_with_the_last_ack_and_an_old_one_ignored(rig):
    rig.send(CLOCK, clock(1))
    assert rig.wait()[2] == 1
    rig.send(CLOCK, clock(1))  # the master did not get it: resent
    rig.send(CLOCK, clock(0))
    d, _, acked, resends = rig.wait(0.1)
    assert d is None and acked == 0 and resends == 1 and rig.last_acked == 1


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
        acked = 0
        for _ in range(5):
            d, _, n, _ = r.wait(0.1)
            assert d is None
            acked += n
        assert acked == 1
        assert r.core.rejected() == {"unsigned": 1, "bad_mac": 1, "replayed": 1}
    finally:
        r.close()


@pytest.mark.parametrize("size", [16, 32, 64, 65, 100, 200])
def test_cpp_verifies_what_python_signs_with_keys_of_any_length(size):
    # HMAC pads a key to SHA-256's 64-byte block, and hashes a longer one first: each
    # side computes that on its own (common/src/auth.cpp, Python's hmac).
    key = bytes((7 * i + size) % 256 for i in range(size))
    r = Rig(keys=[key])
    try:
        r.sealer = auth.Sealer(key, "clock")
        r.send(CLOCK, clock(1))
        assert r.wait()[2] == 1 and r.core.rejected() == {}
        r.sealer = auth.Sealer(key[:-1] + bytes([key[-1] ^ 1]), "clock")  # one bit off
        r.send(CLOCK, clock(2))
        assert r.wait(0.05)[2] == 0 and r.core.rejected() == {"bad_mac": 1}
    finally:
        r.close()


def test_a_policy_that_forbids_its_acks_leaves_the_participant_to_python():
    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        with pytest.raises(RuntimeError, match="does not let tester send on SB_LOCKSTEP_ACK"):
            skillbus_native.QuietFrames(rx.fileno(), CLOCK, ACK, "memq://", NAME, [KEY], "tester",
                                        "SB_LOCKSTEP_ACK someone_else\n")
        with pytest.raises(RuntimeError, match="no socket"):
            skillbus_native.QuietFrames(-1, CLOCK, ACK, "memq://", NAME, [], "", "")
    finally:
        rx.close()


def test_only_a_bus_read_on_the_callers_thread_gets_the_core(monkeypatch):
    memq = LcmBus("memq://")  # LCM's own dispatch, no socket of ours
    assert quiet_frames.for_bus(memq, NAME, CLOCK, ACK) is None
    assert quiet_frames.for_bus(DropEveryNthBus(memq, 3), NAME, CLOCK, ACK) is None  # a test's wrapper
    monkeypatch.setenv(quiet_frames.ENV, "0")
    assert quiet_frames.for_bus(memq, NAME, CLOCK, ACK) is None
