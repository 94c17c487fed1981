"""The canonical sample of every message type, built field by field exactly as
tests/cpp/codec_peer.cpp builds them (the two must agree byte for byte)."""

from skillbus.msgs import (channel_count_t, header_t, lockstep_ack_t, lockstep_clock_t, lockstep_join_t,
                           rpc_counter_t, rpc_reply_t, rpc_request_t, test_sample_t)


def header(frame, sender, seq):
    h = header_t()
    h.frame, h.sim_time_ns, h.sender, h.seq = frame, frame * 10_000_000, sender, seq
    return h


def count(sender, ch, frame, n):
    c = channel_count_t()
    c.sender, c.channel, c.frame, c.count = sender, ch, frame, n
    return c


def samples() -> dict:
    t = test_sample_t()
    t.header = header(7, "codec", 3)
    t.i8, t.i16, t.i32, t.i64 = -8, -1600, -320000, -64000000000
    t.f32, t.f64, t.flag = 1.5, -2.25, True
    t.text = "héllo wörld"
    t.fixed = [1.0, 2.0, 3.0]
    t.values, t.num_values = [1, -2, 3000000000], 3
    t.names, t.num_names = ["a", "", "ccc"], 3
    t.items, t.num_items = [count("s1", "SB_A", 1, 2), count("s2", "SB_B", 3, 4)], 2
    t.rows, t.cols, t.matrix = 2, 3, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]
    t.blob = bytes([0, 1, 254, 255])

    c = lockstep_clock_t()
    c.header, c.frame_period_ns = header(5, "clock", 0), 10_000_000
    c.participants, c.num_participants = ["a", "b"], 2
    c.counts, c.num_counts = [count("a", "SB_A", 4, 1), count("b", "SB_B", 4, 2)], 2
    c.stop, c.stop_reason = True, "because"

    a = lockstep_ack_t()
    a.header = header(5, "a", 0)
    a.counts, a.num_counts = [count("a", "SB_A", 5, 1)], 1
    a.digest, a.error = bytes(range(32)), "oops"

    j = lockstep_join_t()
    j.participant, j.kind, j.pid = "p1", "python", 1234

    q = rpc_request_t()
    q.client_id, q.request_id, q.deadline_ns, q.method = "c:1:ab", 42, 123456789, "add"
    q.payload, q.payload_size = bytes([1, 2, 3, 0, 255]), 5

    r = rpc_reply_t()
    r.client_id, r.request_id, r.method, r.status, r.error = "c:1:ab", 42, "add", rpc_reply_t.ERROR, "bad"
    r.payload, r.payload_size = bytes([9, 8]), 2

    k = rpc_counter_t()
    k.key, k.amount, k.value, k.writes = "k", 5, 10, 2

    return {"test_sample_t": t, "lockstep_clock_t": c, "lockstep_ack_t": a, "lockstep_join_t": j,
            "rpc_request_t": q, "rpc_reply_t": r, "rpc_counter_t": k,
            "channel_count_t": count("s", "SB_X", 9, 3), "header_t": header(1, "h", 4)}
