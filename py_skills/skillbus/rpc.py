"""RPC over the bus, the same protocol as the C++ side (common/include/skillbus/rpc.hpp).

A server of area "WM" takes ``rpc_request_t`` on ``SB_WM_REQ`` and answers with
``rpc_reply_t`` on ``SB_WM_REP``; payloads are LCM encodings of each method's types.

* The client resends the same (client_id, request_id) every ``retry_interval`` until
  the reply arrives or ``timeout`` passes (then :class:`RpcTimeout`, never a hang).
* The server remembers the replies of its last ``memory`` calls and answers a retry from
  that memory without running the method again: a retried write takes effect once.
* Failures come back as typed replies and are raised as :class:`RpcRemoteError`.
* A reply larger than ``CHUNK_BYTES`` comes in chunks: the first with the answer, the
  others when the client asks for them, ``PULL_WINDOW`` at a time (docs/rpc.md).

Example::

    server = RpcServer(bus, "counter")
    server.add_method("add", add_fn, rpc_counter_t, rpc_counter_t)
    client = RpcClient(bus, "counter", "cli")
    reply = client.call("add", request, rpc_counter_t)
"""

from __future__ import annotations

import collections
import os
import time
from typing import Any, Callable

from skillbus.bus import Bus
from skillbus.channels import channel, robot_channel
from skillbus.log import BadInputCounter
from skillbus.msgs import decode, rpc_reply_t, rpc_request_t
from skillbus.rpc_wire import decode_reply, decode_request, encode_reply, encode_request

OK, ERROR, UNKNOWN_METHOD, BAD_REQUEST = (rpc_reply_t.OK, rpc_reply_t.ERROR,
                                          rpc_reply_t.UNKNOWN_METHOD, rpc_reply_t.BAD_REQUEST)
CHUNK_BYTES = 48 * 1024  # the largest reply payload in one message (one LCM datagram): as common/.../rpc.hpp
PULL_WINDOW = 16         # chunks of a large reply asked for at a time
MAX_CHUNKS = 16384       # the most chunks a client takes a reply in (a garbled count must not allocate without bound)


def request_channel(area: str, robot: str | None = None) -> str:
    """SB_<AREA>_REQ, under the robot (`robot`, else the process's: skillbus.channels) when
    the area is one of a robot's own (SKILL, SKPROC_*, MOTION)."""
    name = f"SB_{area.upper()}_REQ"
    return channel(name) if robot is None else robot_channel(name, robot)


def reply_channel(area: str, robot: str | None = None) -> str:
    name = f"SB_{area.upper()}_REP"
    return channel(name) if robot is None else robot_channel(name, robot)


class RpcError(RuntimeError):
    pass


class RpcTimeout(RpcError):
    """No reply within the timeout: ``area`` and ``timeout`` say whose and how long."""

    def __init__(self, message: str, area: str = "", timeout: float = 0.0) -> None:
        super().__init__(message)
        self.area, self.timeout = area, timeout

    def no_answer(self) -> str:
        """The one line a command prints for it (see :func:`no_answer`)."""
        return no_answer(self.area, self.timeout)


# The server of each RPC area, as a command names it when it gets no answer.
SERVERS = {"WM": "world model server", "SKILL": "skill manager", "SIM": "physics server",
           "MOTION": "motion service", "COUNTER": "counter service"}


def no_answer(area: str, timeout: float) -> str:
    """What a command says when the server of `area` does not answer: the server, the
    channel it listens on, and the two usual reasons.

    >>> no_answer("WM", 2.0)
    'no world model server answered on SB_WM_REQ within 2 s: is the system running, in this network namespace?'
    """
    server = SERVERS.get(area.upper(), f"{area} server")
    return (f"no {server} answered on {request_channel(area)} within {timeout:g} s: "
            f"is the system running, in this network namespace?")


class RpcRemoteError(RpcError):
    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


class RpcBadRequest(RpcError):
    """Raise from a method to answer BAD_REQUEST instead of ERROR."""


RawMethod = Callable[[bytes], bytes]


class RpcDefer(Exception):
    """Raised by a method that cannot answer yet: the server keeps the request and runs it
    again at retry_deferred() (a skill process answers a lockstep tick of frame n only
    once it has finished its own frame n)."""


class RpcServer:
    """Answers requests of one area exactly once: a retried request gets the remembered
    answer. The memory is bounded both in answers (`memory`) and in bytes
    (`memory_bytes`: large answers would otherwise pile up), and so are the deferred
    requests (`max_deferred`: the oldest is dropped, as if it had been lost)."""

    def __init__(self, bus: Bus, area: str, memory: int = 4096, memory_bytes: int = 16 << 20,
                 max_deferred: int = 1024) -> None:
        self.bus, self.area, self.memory = bus, area, memory
        self.memory_bytes, self.max_deferred = memory_bytes, max_deferred
        self._answered_bytes = 0
        self.req_channel, self.rep_channel = request_channel(area), reply_channel(area)
        self.methods: dict[str, RawMethod] = {}
        self._answered: collections.OrderedDict[tuple[str, int], Any] = collections.OrderedDict()
        # answers in chunks not all sent yet (a client is pulling them): key -> chunks sent
        self._pulling: dict[tuple[str, int], set[int]] = {}
        self._deferred: collections.OrderedDict[tuple[str, int], tuple[str, bytes]] = collections.OrderedDict()
        self._running: set[tuple[str, int]] = set()  # calls whose method is running
        self.served = self.duplicates = self.expired = 0
        self.bad_input = BadInputCounter(f"rpc-server {area}")
        self._sub = bus.subscribe(self.req_channel, self._on_request)

    def close(self) -> None:
        self.bus.unsubscribe(self._sub)

    @property
    def deferred(self) -> int:
        """Requests deferred (RpcDefer), waiting for retry_deferred()."""
        return len(self._deferred)

    def retry_deferred(self) -> None:
        """Runs the deferred requests again, oldest first (each may defer again)."""
        pending, self._deferred = self._deferred, collections.OrderedDict()
        for ch, data in pending.values():
            self._on_request(ch, data)

    def add_raw_method(self, name: str, method: RawMethod) -> None:
        self.methods[name] = method

    def add_method(self, name: str, fn: Callable[[Any], Any], req_type: type, rep_type: type) -> None:
        """A method on generated LCM types; fn takes the decoded request, returns the reply."""
        def raw(payload: bytes) -> bytes:
            req = decode(req_type, payload)
            if req is None:
                raise RpcBadRequest(f"payload of {name} does not decode as {req_type.__name__}")
            rep = fn(req)
            if not isinstance(rep, rep_type):
                raise RpcError(f"{name} returned {type(rep).__name__}, not {rep_type.__name__}")
            return rep.encode()
        self.methods[name] = raw

    def _send_chunk(self, answer: rpc_reply_t, chunk: int) -> None:
        """Part `chunk` of a remembered answer (its payload whole) on the reply channel."""
        payload = answer.payload
        if len(payload) <= CHUNK_BYTES:  # (one chunk, most answers: sent as it is, not copied)
            answer.chunk, answer.chunks, answer.payload_size = 0, 1, len(payload)
            self.bus.publish(self.rep_channel, encode_reply(answer))
            return
        key = (answer.client_id, answer.request_id)
        if _chunks(len(payload)) > 1:
            sent = self._pulling.setdefault(key, set())
            sent.add(chunk)
            if len(sent) == _chunks(len(payload)):
                del self._pulling[key]
        rep = rpc_reply_t()
        rep.client_id, rep.request_id, rep.method = answer.client_id, answer.request_id, answer.method
        rep.status, rep.error = answer.status, answer.error
        rep.chunk, rep.chunks = chunk, _chunks(len(payload))
        rep.payload = payload[chunk * CHUNK_BYTES:(chunk + 1) * CHUNK_BYTES]
        rep.payload_size = len(rep.payload)
        self.bus.publish(self.rep_channel, encode_reply(rep))

    def _on_request(self, ch: str, data: bytes) -> None:
        req = decode_request(data)
        if req is None:
            self.bad_input.record(ch, "not an rpc_request_t", len(data))
            return
        key = (req.client_id, req.request_id)
        cached = self._answered.get(key)
        if cached is not None:
            if req.chunk == 0:
                self.duplicates += 1  # a retry: answer from memory, do not run the method again
            elif not 0 < req.chunk < _chunks(len(cached.payload)):
                self.bad_input.record(ch, f"chunk {req.chunk} of a reply in {_chunks(len(cached.payload))}", len(data))
                return
            self._send_chunk(cached, req.chunk)
            return
        if req.chunk == 0 and key in self._running:
            # A retry of a call still running: a method that waits (a nested call pumps
            # the bus, as a skill's tick planning a motion does) would otherwise run twice.
            # Its answer goes out when it ends.
            self.duplicates += 1
            return
        rep = rpc_reply_t()
        rep.client_id, rep.request_id, rep.method, rep.status = req.client_id, req.request_id, req.method, OK
        if req.chunk != 0:  # a part of a reply this server no longer has
            rep.status = ERROR
            rep.error = (f"{self.area}.{req.method}: the reply is no longer remembered (larger replies than the "
                         f"server keeps, or the call is too old): call again")
            self._send_chunk(rep, 0)
            return
        if req.deadline_ns and time.time_ns() > req.deadline_ns:
            self.expired += 1  # the client has given up
            return
        method = self.methods.get(req.method)
        if method is None:
            rep.status, rep.error = UNKNOWN_METHOD, f"unknown method '{req.method}' on {self.area}"
        else:
            self._running.add(key)
            try:
                rep.payload = method(bytes(req.payload))
            except RpcDefer:
                self._deferred[key] = (ch, data)
                while len(self._deferred) > self.max_deferred:
                    self._deferred.popitem(last=False)
                    self.bad_input.record(ch, "too many deferred requests: the oldest was dropped", 0)
                return
            except RpcBadRequest as e:
                rep.status, rep.error = BAD_REQUEST, str(e)
            except Exception as e:  # a failing method is an ERROR reply, never silence
                rep.status, rep.error = ERROR, f"{self.area}.{req.method} failed: {e}"
            finally:
                self._running.discard(key)
        self.served += 1
        self._send_chunk(rep, 0)
        self._answered[key] = rep
        self._answered_bytes += len(rep.payload) + 64
        if len(self._answered) > self.memory or self._answered_bytes > self.memory_bytes:
            self._forget_old()

    def _forget_old(self) -> None:
        """Bounded by count and by bytes. The newest is kept whatever its size, and so,
        within twice the bytes, is an answer in chunks a client is still pulling."""
        while len(self._answered) > self.memory or (self._answered_bytes > self.memory_bytes and len(self._answered) > 1):
            victim = next(iter(self._answered))
            if len(self._answered) <= self.memory and self._answered_bytes <= 2 * self.memory_bytes:
                keys = list(self._answered)[:-1]
                victim = next((k for k in keys if k not in self._pulling), victim)
            old = self._answered.pop(victim)
            self._pulling.pop(victim, None)
            self._answered_bytes -= len(old.payload) + 64


def _chunks(size: int) -> int:
    """How many chunks a reply payload of `size` bytes is sent in.

    >>> _chunks(0), _chunks(CHUNK_BYTES), _chunks(CHUNK_BYTES + 1)
    (1, 1, 2)
    """
    return max(1, -(-size // CHUNK_BYTES))


class _Parts:
    """The chunks of a large reply received so far."""

    def __init__(self, chunks: int) -> None:
        self.parts: list[bytes | None] = [None] * chunks
        self.have = 0

    def missing(self, limit: int) -> list[int]:
        return [k for k, p in enumerate(self.parts) if p is None][:limit]


class RpcClient:
    """A client of one area. The client id adds pid and a per-incarnation nonce to the name,
    so a restarted client never collides with its predecessor's request ids."""

    def __init__(self, bus: Bus, area: str, name: str, robot: str | None = None) -> None:
        """`robot`: the robot whose area it is (default: this process's robot)."""
        self.bus, self.area = bus, area
        self.req_channel = request_channel(area, robot)
        self.rep_channel = reply_channel(area, robot)
        self.client_id = f"{name}:{os.getpid()}:{os.urandom(8).hex()}"
        self.next_request_id = 1
        self.retries = 0
        self.bad_input = BadInputCounter(f"rpc-client {area}")
        # Replies by request id for the calls in progress. A dict, not one slot, so that a
        # call made from a handler that runs while another call waits does not steal its reply.
        self._pending: dict[int, Any] = {}
        self._sub = bus.subscribe(self.rep_channel, self._on_reply)

    def close(self) -> None:
        self.bus.unsubscribe(self._sub)

    def _on_reply(self, ch: str, data: bytes) -> None:
        rep = decode_reply(data)
        if rep is None:
            self.bad_input.record(ch, "not an rpc_reply_t", len(data))
            return
        if rep.client_id != self.client_id or rep.request_id not in self._pending:
            return
        got = self._pending[rep.request_id]
        if got is not None and not isinstance(got, _Parts):
            return  # (answered already)
        if rep.chunks <= 1 or rep.status != OK:
            self._pending[rep.request_id] = rep
            return
        # A part of a large reply. The first taken is chunk 0, the call's own answer (the
        # others come only when asked for), with a bounded count; parts of another size of
        # reply (a forged one), empty parts and parts already here are ignored.
        if got is None:
            if rep.chunk != 0:
                return
            if rep.chunks > MAX_CHUNKS:
                rep.status = ERROR
                rep.error = (f"the reply of {rep.method} comes in {rep.chunks} chunks, more than {MAX_CHUNKS} "
                             f"({MAX_CHUNKS * CHUNK_BYTES >> 20} MB): refused")
                self._pending[rep.request_id] = rep
                return
            got = self._pending[rep.request_id] = _Parts(rep.chunks)
        if len(got.parts) != rep.chunks or not 0 <= rep.chunk < rep.chunks or not rep.payload or \
                got.parts[rep.chunk] is not None:
            return
        got.parts[rep.chunk] = bytes(rep.payload)
        got.have += 1
        if got.have == rep.chunks:
            rep.payload = b"".join(got.parts)  # type: ignore[arg-type]
            rep.payload_size, rep.chunk, rep.chunks = len(rep.payload), 0, 1
            self._pending[rep.request_id] = rep

    def _pull(self, method: str, request_id: int, deadline_ns: int, parts: _Parts) -> int:
        """Asks for the first PULL_WINDOW chunks still missing; how many it asked for."""
        pull = rpc_request_t()
        pull.client_id, pull.request_id, pull.deadline_ns, pull.method = self.client_id, request_id, deadline_ns, method
        asked = parts.missing(PULL_WINDOW)
        for k in asked:
            pull.chunk = k
            self.bus.publish(self.req_channel, encode_request(pull))
        return len(asked)

    def call_raw(self, method: str, payload: bytes, timeout: float = 2.0,
                 retry_interval: float = 0.1) -> bytes:
        req = rpc_request_t()
        req.client_id, req.request_id = self.client_id, self.next_request_id
        self.next_request_id += 1
        req.deadline_ns = time.time_ns() + int(timeout * 1e9)
        req.method, req.payload, req.payload_size = method, payload, len(payload)
        buf = encode_request(req)
        rid = req.request_id
        self._pending[rid] = None
        deadline = time.monotonic() + timeout
        attempts = 0
        def waiting() -> bool:
            return self._pending[rid] is None or isinstance(self._pending[rid], _Parts)

        try:
            while waiting():
                now = time.monotonic()
                if now >= deadline:
                    break
                parts = self._pending[rid]
                if isinstance(parts, _Parts):
                    # A large reply has begun: ask for the parts still missing, a window at a
                    # time, and again after a retry interval for those that did not come.
                    had = parts.have
                    self._pull(method, rid, req.deadline_ns, parts)
                    again = min(deadline, now + retry_interval)
                    while waiting() and parts.have - had < PULL_WINDOW:
                        left = again - time.monotonic()
                        if left <= 0:
                            break
                        self.bus.handle(left)
                    continue
                self.bus.publish(self.req_channel, buf)
                if attempts:
                    self.retries += 1
                attempts += 1
                # Back off (x2 per attempt, to 1 s) so that a reply lost to an overrun
                # receiver is not followed by a flood of resent large replies.
                resend_at = min(deadline, now + min(1.0, retry_interval * 2 ** (attempts - 1)))
                while self._pending[rid] is None:  # (until the answer, or its first part)
                    left = resend_at - time.monotonic()
                    if left <= 0:
                        break
                    self.bus.handle(left)
        finally:
            rep = self._pending.pop(rid)
        if isinstance(rep, _Parts):
            raise RpcTimeout(f"rpc {self.area}.{method}: {rep.have} of the {len(rep.parts)} parts of its reply came "
                             f"on {self.rep_channel} within {timeout:.1f} s", self.area, timeout)
        if rep is None:
            raise RpcTimeout(f"rpc {self.area}.{method}: no reply on {self.rep_channel} "
                             f"within {timeout:.1f} s ({attempts} attempts)", self.area, timeout)
        if rep.status != OK:
            raise RpcRemoteError(rep.status, rep.error)
        return bytes(rep.payload)

    def call(self, method: str, request: Any, reply_type: type, timeout: float = 2.0,
             retry_interval: float = 0.1) -> Any:
        out = self.call_raw(method, request.encode(), timeout, retry_interval)
        rep = decode(reply_type, out)
        if rep is None:
            raise RpcError(f"reply of {self.area}.{method} does not decode as {reply_type.__name__}")
        return rep
