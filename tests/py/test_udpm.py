"""skillbus.udpm.Reassembler: LCM's datagrams into messages (the twin of the C++ test,
tests/cpp/test_udpm_receiver.cpp)."""

import struct

from skillbus.udpm import Reassembler


def frag(seq: int, size: int, offset: int, no: int, n: int, body: bytes) -> bytes:
    return b"LC03" + struct.pack(">IIIHH", seq, size, offset, no, n) + body


def test_fragments_in_any_order_make_one_message():
    r = Reassembler()
    first = frag(9, 9, 0, 0, 3, b"SB_Y\0abc")
    assert r.datagram(frag(9, 9, 6, 2, 3, b"ghi"), "a") is None
    assert r.datagram(first, "a") is None
    assert r.datagram(first, "a") is None  # a duplicate changes nothing
    assert r.datagram(frag(4, 3, 0, 0, 2, b"SB_Z\0x"), "b") is None  # another sender meanwhile
    assert r.datagram(frag(9, 9, 3, 1, 3, b"def"), "a") == ("SB_Y", b"abcdefghi")
    assert r.datagram(frag(4, 3, 1, 1, 2, b"yz"), "b") == ("SB_Z", b"xyz")
    assert (r.bad, r.incomplete, r.partials, r.partial_bytes) == (0, 0, {}, 0)


def test_a_message_that_lost_a_fragment_is_counted_when_the_senders_next_begins():
    r = Reassembler()
    assert r.datagram(frag(1, 4, 0, 0, 2, b"C\0ab"), "s") is None
    assert r.datagram(frag(2, 4, 0, 0, 2, b"C\0wx"), "s") is None
    assert r.incomplete == 1
    assert r.datagram(frag(2, 4, 2, 1, 2, b"yz"), "s") == ("C", b"wxyz")


def test_what_does_not_parse_is_counted_never_delivered():
    r = Reassembler()
    bad = [b"", b"LC0", b"LC02", b"LC02" + bytes(4) + b"NO_NUL", b"LC02" + bytes(4) + b"\0no channel",
           b"LC02" + bytes(4) + b"A" * 64 + b"\0", b"XXXX" + bytes(30),
           frag(1, 10, 0, 0, 0, b"C"), frag(1, 10, 0, 2, 2, b"x"), frag(1, 4, 2, 1, 2, b"xyz"),
           frag(1, 1 << 30, 0, 0, 2, b"C\0"), frag(1, 4, 0, 0, 2, b"\xff\xfe\0ab")]
    for d in bad:
        assert r.datagram(d, "s") is None, d
    assert r.bad == len(bad)


def test_partial_messages_are_bounded():
    r = Reassembler()
    for sender in range(1500):
        r.datagram(frag(1, 100, 0, 0, 2, b"C\0" + bytes(50)), sender)
    assert len(r.partials) == 1000 and r.incomplete == 500
    assert r.partial_bytes == 100 * 1000
