"""skillbus.rpc_wire reads and writes the RPC envelope exactly as LCM's generated code:
the same bytes out, the same message (or the same refusal) in, on regular, random and
mutated inputs."""

from __future__ import annotations

import random
import struct

import pytest

from skillbus import rpc_wire
from skillbus.msgs import decode, rpc_reply_t, rpc_request_t

REQUEST_FIELDS = ("client_id", "request_id", "deadline_ns", "method", "chunk", "payload_size", "payload")
REPLY_FIELDS = ("client_id", "request_id", "method", "status", "error", "chunk", "chunks", "payload_size", "payload")


def fields(msg, names) -> tuple | None:
    return None if msg is None else tuple(getattr(msg, n) for n in names)


def text(rng: random.Random) -> str:
    return rng.choice(["", "tick", "skill_mgr-4242-9f3a", "wm.get_element", "é∆ 漢字 🦾", "x" * rng.randrange(0, 300)])


def request(rng: random.Random) -> rpc_request_t:
    r = rpc_request_t()
    r.client_id, r.method = text(rng), text(rng)
    r.request_id, r.deadline_ns = rng.randrange(-2**63, 2**63), rng.choice([0, rng.randrange(0, 2**63)])
    r.chunk = rng.randrange(-2**31, 2**31)
    r.payload = bytes(rng.randrange(256) for _ in range(rng.choice([0, 1, 37, 500])))
    r.payload_size = len(r.payload)
    return r


def reply(rng: random.Random) -> rpc_reply_t:
    r = rpc_reply_t()
    r.client_id, r.method, r.error = text(rng), text(rng), text(rng)
    r.request_id, r.status = rng.randrange(-2**63, 2**63), rng.randrange(-128, 128)
    r.chunk, r.chunks = rng.randrange(-2**31, 2**31), rng.randrange(-2**31, 2**31)
    r.payload = bytes(rng.randrange(256) for _ in range(rng.choice([0, 1, 37, 500])))
    r.payload_size = len(r.payload)
    return r


KINDS = [(request, rpc_request_t, rpc_wire.encode_request, rpc_wire.decode_request, REQUEST_FIELDS),
         (reply, rpc_reply_t, rpc_wire.encode_reply, rpc_wire.decode_reply, REPLY_FIELDS)]


@pytest.mark.parametrize("make, lcm_type, encode, read, names", KINDS)
def test_random_messages_encode_to_lcms_bytes_and_read_back_as_lcm_reads_them(make, lcm_type, encode, read, names):
    rng = random.Random(7)
    for _ in range(300):
        m = make(rng)
        data = encode(m)
        assert data == m.encode()
        got = read(data)
        assert fields(got, names) == fields(decode(lcm_type, data), names) == fields(m, names)
        assert type(got) is lcm_type


@pytest.mark.parametrize("make, lcm_type, encode, read, names", KINDS)
def test_mutated_bytes_are_read_as_lcm_reads_them(make, lcm_type, encode, read, names):
    """Every truncation, a byte changed at every offset, bytes added, length fields made
    huge or zero, strings that are not UTF-8 or lack their NUL: the same message or None."""
    rng = random.Random(11)
    for _ in range(12):
        base = encode(make(rng))
        variants = [base[:n] for n in range(len(base))] + [base + b"\0", base + b"tail"]
        for at in range(len(base)):
            for value in (0, 0xFF, base[at] ^ 0x80):
                variants.append(base[:at] + bytes([value]) + base[at + 1:])
        for at in (8, 12):  # (the first string's length field, and inside it)
            for n in (0, 1, 2**31, 2**32 - 1):
                variants.append(base[:at] + struct.pack(">I", n) + base[at + 4:])
        for v in variants:
            assert fields(read(v), names) == fields(decode(lcm_type, v), names), v


def test_strings_that_lcm_reads_leniently_are_read_the_same():
    """LCM drops a string's last byte whatever it is and replaces bad UTF-8: left to LCM."""
    r = rpc_request_t()
    r.client_id, r.method, r.payload, r.payload_size = "abc", "tick", b"p", 1
    data = r.encode()
    no_nul = data.replace(b"abc\0", b"abcd", 1)
    bad_utf8 = data.replace(b"abc\0", b"a\xffc\0", 1)
    for v in (no_nul, bad_utf8):
        got = rpc_wire.decode_request(v)
        assert got is not None and fields(got, REQUEST_FIELDS) == fields(decode(rpc_request_t, v), REQUEST_FIELDS)
    assert rpc_wire.decode_request(no_nul).client_id == "abc"
    assert rpc_wire.decode_request(bad_utf8).client_id == "a\ufffdc"


def test_a_negative_payload_size_is_read_as_lcm_reads_it():
    r = rpc_reply_t()
    r.client_id, r.method, r.payload, r.payload_size = "c", "m", b"abcd", 4
    data = r.encode()
    forged = data[:-8] + struct.pack(">i", -1) + data[-4:]
    assert fields(rpc_wire.decode_reply(forged), REPLY_FIELDS) == fields(decode(rpc_reply_t, forged), REPLY_FIELDS)


def test_what_is_not_bytes_is_left_to_lcm():
    r = rpc_request_t()
    r.client_id, r.method, r.payload, r.payload_size = "c", "m", b"xyz", 3
    data = r.encode()
    for v in (bytearray(data), memoryview(data)):
        assert fields(rpc_wire.decode_request(v), REQUEST_FIELDS) == fields(decode(rpc_request_t, v), REQUEST_FIELDS)
    assert rpc_wire.decode_request(data[:7]) is None
    assert rpc_wire.decode_reply(data) is None  # (a request is no reply: another fingerprint)


def test_values_lcm_cannot_encode_are_refused_as_lcm_refuses_them():
    rng = random.Random(3)
    cases = [(request, rpc_wire.encode_request, [("request_id", 2**63), ("deadline_ns", -2**63 - 1),
                                                 ("chunk", 2**31), ("client_id", None), ("method", 5),
                                                 ("payload", "text")]),
             (reply, rpc_wire.encode_reply, [("status", 128), ("chunks", -2**31 - 1), ("error", b"bytes")])]
    for make, encode, bad in cases:
        for name, value in bad:
            m = make(rng)
            setattr(m, name, value)
            with pytest.raises(Exception) as lcm:
                m.encode()
            with pytest.raises(type(lcm.value)):
                encode(m)


def test_a_payload_size_other_than_the_payloads_length_encodes_as_lcm_encodes_it():
    """LCM writes payload[:payload_size]: a size too small cuts the payload, a list of ints
    is written as bytes."""
    for size, payload in ((2, b"abcdef"), (3, [1, 2, 3, 4]), (10, b"abc")):
        r = rpc_reply_t()
        r.client_id, r.method, r.payload, r.payload_size = "c", "m", payload, size
        assert rpc_wire.encode_reply(r) == r.encode()
        q = rpc_request_t()
        q.client_id, q.method, q.payload, q.payload_size = "c", "m", payload, size
        assert rpc_wire.encode_request(q) == q.encode()
