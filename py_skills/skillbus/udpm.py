"""Receiving LCM's UDP multicast (udpm://) on the caller's thread.

LCM's C library receives on a thread of its own and wakes the thread that dispatches
through a pipe: two wake-ups, a pipe write and read and a lock per message. In a lockstep
frame every participant takes one clock and the master one ack per participant, so those
hops were a large part of a frame (a Python round trip took 48-52 us through LCM, 28-29
us read here; docs/transport.md). This reader takes datagrams from the socket on the
thread that calls ``handle``, in LCM's wire format (what LCM's publishers, lcm-logger and
lcm-spy use), so it and LCM's own receivers interoperate both ways. Publishing stays
with LCM.

Wire format (LCM's "LCM UDP Multicast" protocol, big-endian):

* short message, one datagram: ``"LC02" | seqno u32 | channel NUL | payload``;
* fragmented message (over ~64 KB): ``"LC03" | seqno u32 | size u32 | offset u32 |
  fragment u16 | fragments u16 | (fragment 0: channel NUL) | bytes``.

What does not parse is counted in ``bad`` and dropped, never raised.
"""

from __future__ import annotations

import collections
import socket
import struct

SHORT_MAGIC = b"LC02"
LONG_MAGIC = b"LC03"
MAX_CHANNEL = 63            # LCM_MAX_CHANNEL_NAME_LENGTH
MAX_MESSAGE = 1 << 28       # LCM_MAX_MESSAGE_SIZE
MAX_PARTIAL_BYTES = 1 << 24  # bytes held in incomplete fragmented messages (as LCM)
MAX_PARTIALS = 1000          # incomplete fragmented messages held (as LCM)
_LONG = struct.Struct(">IIIHH")  # seqno, size, offset, fragment, fragments (after the magic)


class _Partial:
    __slots__ = ("seqno", "channel", "data", "have", "fragments")

    def __init__(self, seqno: int, size: int, fragments: int) -> None:
        self.seqno, self.channel = seqno, ""
        self.data = bytearray(size)
        self.have: set[int] = set()
        self.fragments = fragments


class Reassembler:
    """Turns datagrams into (channel, payload) messages.

    One incomplete fragmented message is kept per sender (LCM sends a message's
    fragments back to back under one lock, so a new sequence number from a sender means
    its previous message lost a fragment); at most MAX_PARTIALS senders and
    MAX_PARTIAL_BYTES bytes, the least recently heard dropped first.

    >>> r = Reassembler()
    >>> r.datagram(b"LC02" + bytes(4) + b"SB_X\\0hello", ("127.0.0.1", 1))
    ('SB_X', b'hello')
    >>> head = b"LC03" + _LONG.pack(7, 6, 0, 0, 2) + b"SB_Y\\0abc"
    >>> r.datagram(head, ("h", 1)) is None
    True
    >>> r.datagram(b"LC03" + _LONG.pack(7, 6, 3, 1, 2) + b"def", ("h", 1))
    ('SB_Y', b'abcdef')
    >>> r.datagram(b"XX", ("h", 1)), r.bad
    (None, 1)
    """

    def __init__(self) -> None:
        self.partials: collections.OrderedDict[object, _Partial] = collections.OrderedDict()
        self.partial_bytes = 0
        self.bad = 0  # datagrams that do not parse, fragments that do not fit
        self.incomplete = 0  # fragmented messages given up (a fragment lost)

    def datagram(self, d: bytes, sender: object) -> tuple[str, bytes] | None:
        magic = d[:4]
        if magic == SHORT_MAGIC:
            end = d.find(b"\0", 8, 8 + MAX_CHANNEL + 1)
            if end <= 8:  # no channel, or one too long
                self.bad += 1
                return None
            try:
                return d[8:end].decode(), d[end + 1:]
            except UnicodeDecodeError:
                self.bad += 1
                return None
        if magic == LONG_MAGIC and len(d) >= 20:
            return self._fragment(d, sender)
        self.bad += 1
        return None

    def _fragment(self, d: bytes, sender: object) -> tuple[str, bytes] | None:
        seqno, size, offset, number, fragments = _LONG.unpack_from(d, 4)
        body = 20
        if size > MAX_MESSAGE or size > MAX_PARTIAL_BYTES or not 0 < fragments or number >= fragments:
            self.bad += 1
            return None
        p = self.partials.get(sender)
        if p is not None and (p.seqno != seqno or len(p.data) != size or p.fragments != fragments):
            self._drop(sender)  # the sender's previous message lost a fragment
            self.incomplete += 1
            p = None
        channel = ""
        if number == 0:
            end = d.find(b"\0", body, body + MAX_CHANNEL + 1)
            if end <= body:
                self.bad += 1
                return None
            try:
                channel = d[body:end].decode()
            except UnicodeDecodeError:
                self.bad += 1
                return None
            body = end + 1
        chunk = memoryview(d)[body:]
        if offset + len(chunk) > size:
            self.bad += 1
            if p is not None:
                self._drop(sender)
            return None
        if p is None:
            p = self._add(sender, seqno, size, fragments)
        if number in p.have:
            return None  # a duplicate
        p.data[offset:offset + len(chunk)] = chunk
        p.have.add(number)
        if number == 0:
            p.channel = channel
        self.partials.move_to_end(sender)
        if len(p.have) < p.fragments:
            return None
        self._drop(sender)
        return p.channel, bytes(p.data)

    def _add(self, sender: object, seqno: int, size: int, fragments: int) -> _Partial:
        while self.partials and (len(self.partials) >= MAX_PARTIALS or
                                 self.partial_bytes + size > MAX_PARTIAL_BYTES):
            self._drop(next(iter(self.partials)))
            self.incomplete += 1
        p = self.partials[sender] = _Partial(seqno, size, fragments)
        self.partial_bytes += size
        return p

    def _drop(self, sender: object) -> None:
        p = self.partials.pop(sender, None)
        if p is not None:
            self.partial_bytes -= len(p.data)


class UdpmReceiver:
    """One multicast group and port, read without blocking on the caller's thread (the
    socket set up as LCM sets up its own: bound to the group and port, address reuse, the
    group joined; a receive buffer of `receive_buffer` bytes)."""

    def __init__(self, group: str, port: int, receive_buffer: int) -> None:
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM, socket.IPPROTO_UDP)
        try:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if receive_buffer > 0:
                s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, receive_buffer)
            s.bind((group, port))
            mreq = struct.pack("4s4s", socket.inet_aton(group), socket.inet_aton("0.0.0.0"))
            s.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP, mreq)
            s.setblocking(False)
        except OSError:
            s.close()
            raise
        self.sock = s
        self.reassembler = Reassembler()

    def fileno(self) -> int:
        return self.sock.fileno()

    def read(self) -> tuple[str, bytes] | None | bool:
        """The message a datagram completes; None for a datagram that completes none;
        False when no datagram is waiting."""
        try:
            d, sender = self.sock.recvfrom(65536)
        except (BlockingIOError, InterruptedError):
            return False
        return self.parse(d, sender)

    def parse(self, d: bytes, sender: object) -> tuple[str, bytes] | None:
        """The message datagram `d` from `sender` completes, or None (as read() does)."""
        if d[:4] == SHORT_MAGIC:  # the common case, inline
            end = d.find(b"\0", 8, 8 + MAX_CHANNEL + 1)
            if end > 8:
                try:
                    return d[8:end].decode(), d[end + 1:]
                except UnicodeDecodeError:
                    pass
        return self.reassembler.datagram(d, sender)

    def close(self) -> None:
        self.sock.close()
