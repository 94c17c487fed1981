import time

import pytest

from skillbus.bus import DropEveryNthBus, open_bus
from skillbus.msgs import rpc_counter_t, rpc_reply_t
from skillbus.rpc import RpcClient, RpcRemoteError, RpcServer, RpcTimeout


def counter_server(bus):
    counters = {}

    def add(req):
        c = counters.setdefault(req.key, rpc_counter_t())
        c.key = req.key
        c.value += req.amount
        c.writes += 1
        return c

    def boom(req):
        raise RuntimeError("the method exploded")

    server = RpcServer(bus, "counter")
    server.add_method("add", add, rpc_counter_t, rpc_counter_t)
    server.add_method("boom", boom, rpc_counter_t, rpc_counter_t)
    return server, counters


def req(key, amount):
    r = rpc_counter_t()
    r.key, r.amount = key, amount
    return r


def test_call_returns_the_reply():
    bus = open_bus("memq://")
    server, counters = counter_server(bus)
    client = RpcClient(bus, "counter", "t")
    assert client.call("add", req("a", 5), rpc_counter_t).value == 5
    rep = client.call("add", req("a", 7), rpc_counter_t)
    assert (rep.value, rep.writes) == (12, 2)


def test_every_write_once_when_every_third_message_per_direction_is_dropped():
    bus = DropEveryNthBus(open_bus("memq://"), 3)
    server, counters = counter_server(bus)
    client = RpcClient(bus, "counter", "t")
    for i in range(1, 301):
        client.call("add", req("k", i), rpc_counter_t, retry_interval=0.005)
    assert counters["k"].writes == 300
    assert counters["k"].value == 300 * 301 // 2
    assert server.duplicates > 0 and client.retries > 0


def test_unknown_method_error_and_bad_request_are_typed():
    bus = open_bus("memq://")
    server, counters = counter_server(bus)
    client = RpcClient(bus, "counter", "t")
    with pytest.raises(RpcRemoteError, match="unknown method 'nope'") as e:
        client.call("nope", req("a", 1), rpc_counter_t)
    assert e.value.status == rpc_reply_t.UNKNOWN_METHOD
    with pytest.raises(RpcRemoteError, match="the method exploded") as e:
        client.call("boom", req("a", 1), rpc_counter_t)
    assert e.value.status == rpc_reply_t.ERROR
    with pytest.raises(RpcRemoteError) as e:
        client.call_raw("add", b"\x01\x02")
    assert e.value.status == rpc_reply_t.BAD_REQUEST
    assert counters == {}


def test_no_server_times_out_within_the_deadline():
    client = RpcClient(open_bus("memq://"), "nobody", "t")
    t0 = time.monotonic()
    with pytest.raises(RpcTimeout, match="no reply on SB_NOBODY_REP within 0.3 s"):
        client.call("add", req("a", 1), rpc_counter_t, timeout=0.3, retry_interval=0.05)
    assert 0.29 <= time.monotonic() - t0 < 1.0


def test_garbage_requests_are_counted_and_ignored():
    bus = open_bus("memq://")
    server, counters = counter_server(bus)
    for junk in (b"", b"\xde\xad\xbe\xef" * 5, b"x" * 300):
        bus.publish("SB_COUNTER_REQ", junk)
    client = RpcClient(bus, "counter", "t")
    assert client.call("add", req("a", 2), rpc_counter_t).value == 2
    assert server.bad_input.total == 3


def test_server_memory_is_bounded():
    bus = open_bus("memq://")
    server = RpcServer(bus, "counter", memory=10)
    server.add_method("add", lambda r: r, rpc_counter_t, rpc_counter_t)
    client = RpcClient(bus, "counter", "t")
    for i in range(50):
        client.call("add", req("a", i), rpc_counter_t)
    assert len(server._answered) == 10


def test_server_memory_is_bounded_in_bytes():
    """Large answers: the remembered ones stay within memory_bytes (300 answers of 100 KB
    would be 30 MB)."""
    bus = open_bus("memq://")
    server = RpcServer(bus, "counter", memory=4096, memory_bytes=1 << 20)
    server.add_method("add", lambda r: r, rpc_counter_t, rpc_counter_t)
    client = RpcClient(bus, "counter", "t")
    for i in range(300):
        client.call("add", req("k" * 100_000, i), rpc_counter_t)
    assert server._answered_bytes <= 1 << 20 and 5 <= len(server._answered) <= 11
    assert server._answered_bytes == sum(len(a.payload) + 64 for a in server._answered.values())


def test_deferred_requests_are_bounded():
    from skillbus.rpc import RpcDefer
    bus = open_bus("memq://")
    server = RpcServer(bus, "counter", max_deferred=5)

    def later(r):
        raise RpcDefer()

    server.add_method("later", later, rpc_counter_t, rpc_counter_t)
    client = RpcClient(bus, "counter", "t")
    for i in range(20):
        with pytest.raises(RpcTimeout):
            client.call("later", req("a", i), rpc_counter_t, timeout=0.05)
    assert len(server._deferred) == 5


class OneDatagramBus(DropEveryNthBus):
    """As UDP with a busy receiver: a message larger than one datagram never arrives
    (LCM loses a whole message with any of its fragments), and every third is lost."""

    def publish(self, channel, data):
        if len(data) > 60_000:
            self.dropped += 1
            return
        super().publish(channel, data)


def test_a_large_reply_arrives_in_chunks_through_a_lossy_bus():
    """A 1 MB reply is 22 chunks of one datagram each: the first comes with the answer, the
    client asks for the rest a window at a time and again for those lost (every third
    message in each direction here), and the method runs once."""
    from skillbus.rpc import CHUNK_BYTES
    bus = OneDatagramBus(open_bus("memq://"), 3)
    runs = []

    def big(r):  # a small request, a 1 MB reply
        runs.append(1)
        return req("".join(chr(65 + i % 26) for i in range(1_000_000)), r.amount)

    server = RpcServer(bus, "counter")
    server.add_method("big", big, rpc_counter_t, rpc_counter_t)
    client = RpcClient(bus, "counter", "t")
    rep = client.call("big", req("", 7), rpc_counter_t, retry_interval=0.005, timeout=10)
    assert len(rep.key) == 1_000_000 and rep.key[:3] == "ABC" and rep.amount == 7 and runs == [1]
    assert len(server._answered[(client.client_id, 1)].payload) > 20 * CHUNK_BYTES


def test_chunk_requests_out_of_range_or_for_forgotten_replies():
    from skillbus.msgs import rpc_request_t
    bus = open_bus("memq://")
    server, _ = counter_server(bus)
    client = RpcClient(bus, "counter", "t")
    client.call("add", req("a", 1), rpc_counter_t)
    got = []
    bus.subscribe(server.rep_channel, lambda ch, data: got.append(data))
    pull = rpc_request_t()
    pull.client_id, pull.request_id, pull.method, pull.chunk = client.client_id, 1, "add", 3  # a 1-chunk reply
    bus.publish(server.req_channel, pull.encode())
    while bus.handle(0.02):
        pass
    assert got == [] and server.bad_input.total == 1
    pull.request_id = 99  # never called: an error reply, not silence, and no method run
    bus.publish(server.req_channel, pull.encode())
    while bus.handle(0.02):
        pass
    rep = rpc_reply_t.decode(got[-1])
    assert rep.status == rpc_reply_t.ERROR and "no longer remembered" in rep.error and server.served == 1


def test_a_reply_that_claims_too_many_chunks_is_refused_not_allocated():
    from skillbus.msgs import rpc_request_t
    from skillbus.rpc import MAX_CHUNKS, reply_channel, request_channel
    bus = open_bus("memq://")

    def forge(ch, data):  # a "server" that answers every call with an absurd chunk count
        r = rpc_request_t.decode(data)
        rep = rpc_reply_t()
        rep.client_id, rep.request_id, rep.method, rep.status = r.client_id, r.request_id, r.method, rpc_reply_t.OK
        rep.chunk, rep.chunks, rep.payload, rep.payload_size = 0, 1 << 30, b"x", 1
        bus.publish(reply_channel("counter"), rep.encode())

    bus.subscribe(request_channel("counter"), forge)
    client = RpcClient(bus, "counter", "t")
    with pytest.raises(RpcRemoteError, match=f"more than {MAX_CHUNKS}"):
        client.call("add", req("a", 1), rpc_counter_t, timeout=2)


def test_an_answer_a_client_is_still_pulling_outlives_newer_answers():
    """Memory of 1 MB: a 600 KB answer whose chunks are not all sent yet is kept while 20
    newer 100 KB answers come and go (within twice the memory); then it is pulled whole."""
    from skillbus.msgs import rpc_request_t
    bus = open_bus("memq://")
    server = RpcServer(bus, "counter", memory_bytes=1 << 20)
    server.add_method("big", lambda r: req("B" * 600_000, 0), rpc_counter_t, rpc_counter_t)
    server.add_method("add", lambda r: req("k" * 100_000, r.amount), rpc_counter_t, rpc_counter_t)
    got = []
    bus.subscribe(server.rep_channel, lambda ch, data: got.append(rpc_reply_t.decode(data)))
    call = rpc_request_t()
    call.client_id, call.request_id, call.method = "slow-reader", 1, "big"
    call.payload = req("", 0).encode()
    call.payload_size = len(call.payload)
    bus.publish(server.req_channel, call.encode())  # its first chunk comes; the reader is slow to pull
    while bus.handle(0.01):
        pass
    other = RpcClient(bus, "counter", "busy")
    for i in range(20):
        other.call("add", req("", i), rpc_counter_t)
    assert ("slow-reader", 1) in server._answered
    first = got[0]
    assert first.chunks == 13
    call.payload, call.payload_size = b"", 0
    for k in range(1, first.chunks):
        call.chunk = k
        bus.publish(server.req_channel, call.encode())
    while bus.handle(0.01):
        pass
    parts = {r.chunk: r.payload for r in got if r.client_id == "slow-reader"}
    assert all(r.status == rpc_reply_t.OK for r in got if r.client_id == "slow-reader")
    assert len(parts) == first.chunks and ("slow-reader", 1) not in server._pulling


def test_a_retry_that_arrives_while_the_call_still_runs_does_not_run_it_again():
    # A method that waits pumps the bus (a skill's tick planning a motion calls the motion
    # service); the client's retry of the same call arrives meanwhile. Seen on DDS, where
    # the skill process then sent the arm the same trajectory twice.
    from skillbus.rpc import request_channel
    bus = open_bus("memq://")
    raw = []
    bus.subscribe(request_channel("slow"), lambda ch, data: raw.append(data))
    runs = []

    def slow(r):
        runs.append(r.key)
        if len(runs) == 1:
            bus.publish(request_channel("slow"), raw[0])  # the retry, as it arrives meanwhile
            end = time.monotonic() + 0.2
            while time.monotonic() < end:
                bus.handle(0.01)
        return r

    server = RpcServer(bus, "slow")
    server.add_method("run", slow, rpc_counter_t, rpc_counter_t)
    client = RpcClient(bus, "slow", "t")
    assert client.call("run", req("a", 1), rpc_counter_t, timeout=5).key == "a"
    assert runs == ["a"]
    assert server.duplicates >= 1  # (the client may have retried once more itself)
    # and a retry after it ended is answered from memory, still not run again
    while bus.handle(0.01):  # (the client's own last retry, if one is still queued)
        pass
    before = server.duplicates
    bus.publish(request_channel("slow"), raw[0])
    while bus.handle(0.01):
        pass
    assert runs == ["a"] and server.duplicates == before + 1
