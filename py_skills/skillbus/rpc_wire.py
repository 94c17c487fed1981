"""The RPC envelope (rpc_request_t, rpc_reply_t) read and written in a few calls.

Every RPC a Python process serves or makes goes through these two types; LCM's generated
Python reads and writes them a field at a time through a BytesIO (about 30 calls each
way), which was a sixth of a skill process's work per tick (docs/benchmarks.md).

The results are LCM's own: ``decode_request``/``decode_reply`` return exactly what
``skillbus.msgs.decode`` returns for the same bytes, and ``encode_request``/
``encode_reply`` give exactly ``msg.encode()``'s bytes (and raise where it raises).
The fast path takes only the regular case (strings that end in their NUL and are valid
UTF-8, a payload that is the rest of the message); anything else goes to LCM's decoder,
which then decides (tests/py/test_rpc_wire.py compares both on mutated and random bytes).
"""

from __future__ import annotations

import struct

from skillbus.msgs import decode, rpc_reply_t, rpc_request_t

_REQUEST_FP = rpc_request_t._get_packed_fingerprint()
_REPLY_FP = rpc_reply_t._get_packed_fingerprint()
_U32 = struct.Struct(">I")
_Q = struct.Struct(">q")      # request_id
_B = struct.Struct(">b")      # status
_QQ = struct.Struct(">qq")    # request_id, deadline_ns
_QQI = struct.Struct(">qqI")  # request_id, deadline_ns, the method's length
_II = struct.Struct(">ii")    # chunk, payload_size
_QI = struct.Struct(">qI")    # request_id, the method's length
_BI = struct.Struct(">bI")    # status, the error's length
_III = struct.Struct(">iii")  # chunk, chunks, payload_size
_NUL = b"\0"


def _text_at(data: bytes, at: int) -> tuple[str, int] | None:
    """The string whose u32 length is at `at` and the offset after it, or None when it is
    not the regular case (empty, cut short, not ended by its NUL, not UTF-8)."""
    n = _U32.unpack_from(data, at)[0]
    end = at + 4 + n
    if n == 0 or end > len(data) or data[end - 1] != 0:
        return None
    try:
        return data[at + 4:end - 1].decode(), end
    except UnicodeDecodeError:
        return None


def decode_request(data: bytes) -> rpc_request_t | None:
    """As ``msgs.decode(rpc_request_t, data)``."""
    if type(data) is not bytes or data[:8] != _REQUEST_FP:
        return decode(rpc_request_t, data)
    try:
        got = _text_at(data, 8)
        if got is not None:
            client_id, at = got
            request_id, deadline_ns = _QQ.unpack_from(data, at)
            got = _text_at(data, at + 16)
        if got is not None:
            method, at = got
            chunk, size = _II.unpack_from(data, at)
            at += 8
            if size >= 0 and at + size == len(data):
                r = rpc_request_t()
                r.client_id, r.request_id, r.deadline_ns, r.method = client_id, request_id, deadline_ns, method
                r.chunk, r.payload_size, r.payload = chunk, size, data[at:]
                return r
    except struct.error:
        pass
    return decode(rpc_request_t, data)


def decode_reply(data: bytes) -> rpc_reply_t | None:
    """As ``msgs.decode(rpc_reply_t, data)``."""
    if type(data) is not bytes or data[:8] != _REPLY_FP:
        return decode(rpc_reply_t, data)
    try:
        got = _text_at(data, 8)
        if got is not None:
            client_id, at = got
            request_id = _Q.unpack_from(data, at)[0]
            got = _text_at(data, at + 8)
        if got is not None:
            method, at = got
            status = _B.unpack_from(data, at)[0]
            got = _text_at(data, at + 1)
        if got is not None:
            error, at = got
            chunk, chunks, size = _III.unpack_from(data, at)
            at += 12
            if size >= 0 and at + size == len(data):
                r = rpc_reply_t()
                r.client_id, r.request_id, r.method, r.status, r.error = client_id, request_id, method, status, error
                r.chunk, r.chunks, r.payload_size, r.payload = chunk, chunks, size, data[at:]
                return r
    except struct.error:
        pass
    return decode(rpc_reply_t, data)


def _payload(payload, size: int) -> bytes:
    """What LCM writes of a payload: its first `size` bytes (a list of ints as bytes); the
    bytes themselves when they are bytes already (not copied twice)."""
    out = payload[:size]
    return out if type(out) is bytes else bytes(bytearray(out))


def encode_request(r: rpc_request_t) -> bytes:
    """As ``r.encode()``."""
    client_id, method = r.client_id.encode("utf-8"), r.method.encode("utf-8")
    return b"".join((_REQUEST_FP, _U32.pack(len(client_id) + 1), client_id, _NUL,
                     _QQI.pack(r.request_id, r.deadline_ns, len(method) + 1), method, _NUL,
                     _II.pack(r.chunk, r.payload_size), _payload(r.payload, r.payload_size)))


def encode_reply(r: rpc_reply_t) -> bytes:
    """As ``r.encode()``."""
    client_id, method, error = r.client_id.encode("utf-8"), r.method.encode("utf-8"), r.error.encode("utf-8")
    return b"".join((_REPLY_FP, _U32.pack(len(client_id) + 1), client_id, _NUL,
                     _QI.pack(r.request_id, len(method) + 1), method, _NUL,
                     _BI.pack(r.status, len(error) + 1), error, _NUL,
                     _III.pack(r.chunk, r.chunks, r.payload_size), _payload(r.payload, r.payload_size)))
