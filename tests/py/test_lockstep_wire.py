"""skillbus.lockstep_wire reads and writes exactly what LCM's generated classes do."""

import random

import pytest

from skillbus import lockstep_wire
from skillbus.lockstep_wire import AckEncoder, python_decode_clock, read_header
from skillbus.msgs import channel_count_t, header_t, lockstep_ack_t, lockstep_clock_t

NAMES = ["", "p0", "skills-process", "grip\u00e9", "x" * 70]


def random_counts(rng: random.Random) -> list[channel_count_t]:
    out = []
    for _ in range(rng.randrange(0, 5)):
        c = channel_count_t()
        c.sender, c.channel = rng.choice(NAMES), rng.choice(NAMES)
        c.frame, c.count = rng.randrange(-2**63, 2**63), rng.randrange(-2**31, 2**31)
        out.append(c)
    return out


def random_clock(rng: random.Random) -> lockstep_clock_t:
    c = lockstep_clock_t()
    c.header.frame, c.header.sim_time_ns = rng.randrange(-2**63, 2**63), rng.randrange(-2**63, 2**63)
    c.header.sender, c.header.seq = rng.choice(NAMES), rng.randrange(-2**31, 2**31)
    c.frame_period_ns = rng.randrange(-2**63, 2**63)
    c.participants = [rng.choice(NAMES) for _ in range(rng.randrange(0, 9))]
    c.num_participants = len(c.participants)
    c.counts = random_counts(rng)
    c.num_counts = len(c.counts)
    c.stop = rng.random() < 0.5
    c.stop_reason = rng.choice(NAMES)
    return c


def native_decode_clock():
    from skillbus import native
    if native.module() is None:
        pytest.fail("skillbus_native is not built (make build)")
    assert lockstep_wire.decode_clock is native.module().decode_clock  # (what the participants use)
    return native.module().decode_clock


# Both decoders: skillbus_native's (what runs) and Python's (SKILLBUS_NATIVE=0).
DECODERS = [pytest.param(lambda: python_decode_clock, id="python"), pytest.param(native_decode_clock, id="native")]


@pytest.mark.parametrize("decoder", DECODERS)
def test_clocks_decode_as_the_generated_decoder_decodes_them(decoder):
    decode_clock = decoder()
    rng = random.Random(1)
    for _ in range(500):
        data = random_clock(rng).encode()
        fast, slow = decode_clock(data), lockstep_clock_t.decode(data)
        assert fast.encode() == data == slow.encode()
        assert (fast.header.frame, fast.header.sender, fast.participants, fast.stop, fast.stop_reason) == \
            (slow.header.frame, slow.header.sender, slow.participants, slow.stop, slow.stop_reason)
        assert [(c.sender, c.channel, c.frame, c.count) for c in fast.counts] == \
            [(c.sender, c.channel, c.frame, c.count) for c in slow.counts]
        assert (type(fast), type(fast.header), type(fast.participants), type(fast.counts), type(fast.stop)) == \
            (type(slow), type(slow.header), list, list, bool)
        assert all(type(c) is channel_count_t for c in fast.counts)
        assert (fast.num_participants, fast.num_counts, fast.frame_period_ns, fast.header.seq) == \
            (slow.num_participants, slow.num_counts, slow.frame_period_ns, slow.header.seq)


@pytest.mark.parametrize("decoder", DECODERS)
def test_a_damaged_clock_is_a_value_error_never_another_exception(decoder):
    decode_clock = decoder()
    rng = random.Random(2)
    data = random_clock(rng).encode()
    with pytest.raises(ValueError, match="fingerprint"):
        decode_clock(lockstep_ack_t().encode()[:8] + data[8:])
    for cut in range(8, len(data)):
        with pytest.raises(ValueError):
            decode_clock(data[:cut])
    with pytest.raises(ValueError, match="after its end"):
        decode_clock(data + b"\0")
    # A length that claims more than the message holds, and a negative one.
    c = lockstep_clock_t()
    c.participants, c.num_participants = ["a"], 1
    good = c.encode()
    at = good.index(b"\x00\x00\x00\x01", 8 + 8 + 8 + 4 + 1 + 4 + 8)  # num_participants
    for bad in (b"\x7f\xff\xff\xff", b"\xff\xff\xff\xff"):
        with pytest.raises(ValueError):
            decode_clock(good[:at] + bad + good[at + 4:])
    for _ in range(2000):  # random damage: a ValueError or a clock, nothing else; the same as Python's
        b = bytes(bytearray(data)[:8]) + bytes(rng.randrange(256) if rng.random() < 0.05 else x for x in data[8:])
        try:
            got = decode_clock(b)
        except ValueError:
            with pytest.raises(ValueError):
                python_decode_clock(b)
        else:
            assert got.encode() == python_decode_clock(b).encode()
    assert decode_clock(bytearray(data)).encode() == data  # (any buffer, as Python's reads one)


def test_acks_encode_as_the_generated_encoder_encodes_them():
    rng = random.Random(3)
    for name in NAMES:
        enc = AckEncoder(name)
        for _ in range(50):
            a = lockstep_ack_t()
            a.header.frame, a.header.sim_time_ns = rng.randrange(-2**63, 2**63), rng.randrange(-2**63, 2**63)
            a.header.sender, a.header.seq = name, 0
            a.counts = random_counts(rng)
            a.num_counts = len(a.counts)
            a.digest = rng.randbytes(32)
            a.error = rng.choice(NAMES)
            assert enc.encode(a.header.frame, a.header.sim_time_ns, a.counts, a.digest, a.error) == a.encode()
    with pytest.raises(ValueError, match="32"):
        AckEncoder("p").encode(0, 0, [], bytes(31), "")


def test_read_header_reads_a_stamp():
    h = header_t()
    h.frame, h.sim_time_ns, h.sender, h.seq = 7, 70, "me", 3
    m = lockstep_ack_t()
    m.header, m.digest = h, bytes(32)
    got, end = read_header(m.encode(), 8)
    assert (got.frame, got.sim_time_ns, got.sender, got.seq, end) == (7, 70, "me", 3, 8 + 8 + 8 + 4 + 3 + 4)


@pytest.mark.parametrize("decoder", DECODERS)
def test_what_is_not_bytes_is_no_clock(decoder):
    decode_clock = decoder()
    data = random_clock(random.Random(4)).encode()
    assert decode_clock(bytearray(data)).encode() == data
    for other in (data.decode("latin-1"), memoryview(data), None, 7, [data]):
        with pytest.raises(ValueError, match="not a lockstep_clock_t"):
            decode_clock(other)
