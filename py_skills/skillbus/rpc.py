"""RPC over the bus, the same protocol as the C++ side (common/include/skillbus/rpc.hpp).

A server of area "WM" takes ``rpc_request_t`` on ``SB_WM_REQ`` and answers with
``rpc_reply_t`` on ``SB_WM_REP``; payloads are LCM encodings of each method's types.

* The client resends the same (client_id, request_id) every ``retry_interval`` until
  the reply arrives or ``timeout`` passes (then :class:`RpcTimeout`, never a hang).
* The server remembers the replies of its last ``memory`` calls and answers a retry from
  that memory without running the method again: a retried write takes effect once.
* Failures come back as typed replies and are raised as :class:`RpcRemoteError`.

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

from skillbus.bus import Bus, channel
from skillbus.log import BadInputCounter
from skillbus.msgs import decode, rpc_reply_t, rpc_request_t

OK, ERROR, UNKNOWN_METHOD, BAD_REQUEST = (rpc_reply_t.OK, rpc_reply_t.ERROR,
                                          rpc_reply_t.UNKNOWN_METHOD, rpc_reply_t.BAD_REQUEST)


def request_channel(area: str) -> str:
    return channel(f"SB_{area.upper()}_REQ")


def reply_channel(area: str) -> str:
    return channel(f"SB_{area.upper()}_REP")


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
        self._answered: collections.OrderedDict[tuple[str, int], bytes] = collections.OrderedDict()
        self._deferred: collections.OrderedDict[tuple[str, int], tuple[str, bytes]] = collections.OrderedDict()
        self.served = self.duplicates = self.expired = 0
        self.bad_input = BadInputCounter(f"rpc-server {area}")
        self._sub = bus.subscribe(self.req_channel, self._on_request)

    def close(self) -> None:
        self.bus.unsubscribe(self._sub)

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

    def _on_request(self, ch: str, data: bytes) -> None:
        req = decode(rpc_request_t, data)
        if req is None:
            self.bad_input.record(ch, "not an rpc_request_t", len(data))
            return
        key = (req.client_id, req.request_id)
        cached = self._answered.get(key)
        if cached is not None:
            self.duplicates += 1  # a retry: answer from memory, do not run the method again
            self.bus.publish(self.rep_channel, cached)
            return
        if req.deadline_ns and time.time_ns() > req.deadline_ns:
            self.expired += 1  # the client has given up
            return
        rep = rpc_reply_t()
        rep.client_id, rep.request_id, rep.method, rep.status = req.client_id, req.request_id, req.method, OK
        method = self.methods.get(req.method)
        if method is None:
            rep.status, rep.error = UNKNOWN_METHOD, f"unknown method '{req.method}' on {self.area}"
        else:
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
        rep.payload_size = len(rep.payload)
        self.served += 1
        buf = rep.encode()
        self.bus.publish(self.rep_channel, buf)
        self._answered[key] = buf
        self._answered_bytes += len(buf)
        while len(self._answered) > self.memory or (self._answered_bytes > self.memory_bytes and len(self._answered) > 1):
            _, old = self._answered.popitem(last=False)
            self._answered_bytes -= len(old)


class RpcClient:
    """A client of one area. The client id adds pid and a per-incarnation nonce to the name,
    so a restarted client never collides with its predecessor's request ids."""

    def __init__(self, bus: Bus, area: str, name: str) -> None:
        self.bus, self.area = bus, area
        self.req_channel = request_channel(area)
        self.client_id = f"{name}:{os.getpid()}:{os.urandom(8).hex()}"
        self.next_request_id = 1
        self.retries = 0
        self.bad_input = BadInputCounter(f"rpc-client {area}")
        # Replies by request id for the calls in progress. A dict, not one slot, so that a
        # call made from a handler that runs while another call waits does not steal its reply.
        self._pending: dict[int, Any] = {}
        self._sub = bus.subscribe(reply_channel(area), self._on_reply)

    def close(self) -> None:
        self.bus.unsubscribe(self._sub)

    def _on_reply(self, ch: str, data: bytes) -> None:
        rep = decode(rpc_reply_t, data)
        if rep is None:
            self.bad_input.record(ch, "not an rpc_reply_t", len(data))
            return
        if rep.client_id == self.client_id and self._pending.get(rep.request_id, 0) is None:
            self._pending[rep.request_id] = rep

    def call_raw(self, method: str, payload: bytes, timeout: float = 2.0,
                 retry_interval: float = 0.1) -> bytes:
        req = rpc_request_t()
        req.client_id, req.request_id = self.client_id, self.next_request_id
        self.next_request_id += 1
        req.deadline_ns = time.time_ns() + int(timeout * 1e9)
        req.method, req.payload, req.payload_size = method, payload, len(payload)
        buf = req.encode()
        rid = req.request_id
        self._pending[rid] = None
        deadline = time.monotonic() + timeout
        attempts = 0
        try:
            while self._pending[rid] is None:
                now = time.monotonic()
                if now >= deadline:
                    break
                self.bus.publish(self.req_channel, buf)
                if attempts:
                    self.retries += 1
                attempts += 1
                # Back off (x2 per attempt, to 1 s) so that a reply lost to an overrun
                # receiver is not followed by a flood of resent large replies.
                resend_at = min(deadline, now + min(1.0, retry_interval * 2 ** (attempts - 1)))
                while self._pending[rid] is None:
                    left = resend_at - time.monotonic()
                    if left <= 0:
                        break
                    self.bus.handle(left)
        finally:
            rep = self._pending.pop(rid)
        if rep is None:
            raise RpcTimeout(f"rpc {self.area}.{method}: no reply on {reply_channel(self.area)} "
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
