"""The lockstep clock and ack off and onto the wire, fast.

Why a codec of our own: every Python participant decodes one ``lockstep_clock_t`` and
encodes one ``lockstep_ack_t`` per frame, and LCM's generated Python does it field by
field through a BytesIO: about 20 µs of the 55 µs a bare Python participant spent per
frame (docs/benchmarks.md). These read and write exactly the bytes of the generated
classes with precompiled structs and return the generated classes' objects;
tests/py/test_lockstep_wire.py compares both ways on random messages. The clock is read
by skillbus_native when it is built (about 26 µs a frame in Python with the demo's
counts, a few in C++), by python_decode_clock otherwise.
"""

from __future__ import annotations

import struct

from skillbus.msgs import channel_count_t, header_t, lockstep_ack_t, lockstep_clock_t

_CLOCK = lockstep_clock_t._get_packed_fingerprint()
_ACK = lockstep_ack_t._get_packed_fingerprint()
_I64I64U32 = struct.Struct(">qqI")
_I32 = struct.Struct(">i")
_U32 = struct.Struct(">I")
_I64I32 = struct.Struct(">qi")
_I64 = struct.Struct(">q")
_new_clock, _new_header, _new_count = lockstep_clock_t.__new__, header_t.__new__, channel_count_t.__new__


def _string(buf: bytes, pos: int) -> tuple[str, int]:
    (n,) = _U32.unpack_from(buf, pos)
    end = pos + 4 + n
    if n < 1 or end > len(buf):
        raise ValueError("a string cut short")
    return buf[pos + 4:end - 1].decode("utf-8", "replace"), end


def read_header(buf: bytes, pos: int) -> tuple[header_t, int]:
    """The header_t at `pos` and the position after it (ValueError, struct.error when cut)."""
    frame, sim_time, n = _I64I64U32.unpack_from(buf, pos)
    start = pos + 20
    end = start + n
    if n < 1 or end + 4 > len(buf):
        raise ValueError("a header cut short")
    h = _new_header(header_t)
    h.frame, h.sim_time_ns = frame, sim_time
    h.sender = buf[start:end - 1].decode("utf-8", "replace")
    (h.seq,) = _I32.unpack_from(buf, end)
    return h, end + 4


def _counts(buf: bytes, pos: int) -> tuple[list[channel_count_t], int]:
    (n,) = _I32.unpack_from(buf, pos)
    pos += 4
    if n < 0 or n > len(buf) - pos:
        raise ValueError(f"{n} counts")
    out = []
    for _ in range(n):
        c = _new_count(channel_count_t)
        c.sender, pos = _string(buf, pos)
        c.channel, pos = _string(buf, pos)
        c.frame, c.count = _I64I32.unpack_from(buf, pos)
        pos += 12
        out.append(c)
    return out, pos


def python_decode_clock(data: bytes) -> lockstep_clock_t:
    """The clock in `data`; ValueError when it is no lockstep_clock_t (another type,
    cut short, a negative or impossible length, or bytes left over). decode_clock is
    skillbus_native's twin of it when built (the same fields and refusals)."""
    if not isinstance(data, (bytes, bytearray)):
        raise ValueError(f"not a lockstep_clock_t ({type(data).__name__}, not bytes)")
    if data[:8] != _CLOCK:
        raise ValueError("not a lockstep_clock_t (its fingerprint differs)")
    try:
        c = _new_clock(lockstep_clock_t)
        c.header, pos = read_header(data, 8)
        c.frame_period_ns, n = _I64I32.unpack_from(data, pos)
        pos += 12
        if n < 0 or n > len(data) - pos:
            raise ValueError(f"{n} participants")
        c.num_participants = n
        participants = []
        for _ in range(n):
            p, pos = _string(data, pos)
            participants.append(p)
        c.participants = participants
        c.counts, pos = _counts(data, pos)
        c.num_counts = len(c.counts)
        c.stop = data[pos] != 0
        c.stop_reason, pos = _string(data, pos + 1)
    except (struct.error, IndexError) as e:
        raise ValueError(f"a lockstep_clock_t cut short: {e}") from None
    if pos != len(data):
        raise ValueError(f"a lockstep_clock_t with {len(data) - pos} bytes after its end")
    return c


def _native_decode_clock():
    """skillbus_native's decode_clock, given the generated classes; None without it."""
    from skillbus import native
    lib = native.module()
    if lib is None or not hasattr(lib, "decode_clock"):
        return None
    lib.set_clock_types(_CLOCK, lockstep_clock_t, header_t, channel_count_t)
    return lib.decode_clock


decode_clock = _native_decode_clock() or python_decode_clock


def _string_bytes(s: str) -> bytes:
    b = s.encode("utf-8")
    return _U32.pack(len(b) + 1) + b + b"\0"


class AckEncoder:
    """Encodes the acks of one participant: its name is encoded once.

    >>> a = AckEncoder("p1").encode(3, 30_000_000, [], bytes(32), "")
    >>> m = lockstep_ack_t.decode(a); (m.header.frame, m.header.sender, m.num_counts)
    (3, 'p1', 0)
    """

    def __init__(self, sender: str) -> None:
        self.sender = sender
        self._sender = _string_bytes(sender)

    def encode(self, frame: int, sim_time_ns: int, counts: list[channel_count_t], digest: bytes,
               error: str) -> bytes:
        if len(digest) != 32:
            raise ValueError(f"a digest of {len(digest)} bytes (32 needed)")
        parts = [_ACK, _I64.pack(frame), _I64.pack(sim_time_ns), self._sender, _I32.pack(0),
                 _I32.pack(len(counts))]
        for c in counts:
            parts += (_string_bytes(c.sender), _string_bytes(c.channel), _I64I32.pack(c.frame, c.count))
        parts += (digest, _string_bytes(error))
        return b"".join(parts)
