"""The rules that keep a skill's tick deterministic under lockstep (docs/skills.md,
"Lockstep"): a request deferred until the process has finished the tick's frame, and
publications from a tick held for the next frame."""

from skillbus import tick_context
from skillbus.bus import open_bus
from skillbus.lockstep import LockstepParticipant
from skillbus.msgs import rpc_counter_t, test_sample_t
from skillbus.rpc import RpcClient, RpcDefer, RpcServer


def test_a_deferred_request_is_answered_once_retried():
    bus = open_bus("memq://")
    server = RpcServer(bus, "T")
    ready = {"yes": False, "calls": 0}

    def add(r):
        ready["calls"] += 1
        if not ready["yes"]:
            raise RpcDefer()
        r.amount += 1
        return r

    server.add_method("add", add, rpc_counter_t, rpc_counter_t)
    client = RpcClient(bus, "T", "c")
    req = rpc_counter_t()
    req.key, req.amount = "k", 41
    client_id = client.client_id
    # A request that arrives too early gets no answer (not an error) and is kept.
    from skillbus.msgs import rpc_request_t
    m = rpc_request_t()
    m.client_id, m.request_id, m.method = client_id, 1, "add"
    m.payload = req.encode()
    m.payload_size = len(m.payload)
    replies = []
    bus.subscribe("SB_T_REP", lambda ch, d: replies.append(d))
    bus.publish("SB_T_REQ", m.encode())
    bus.handle(0.1)
    assert replies == [] and ready["calls"] == 1
    ready["yes"] = True
    server.retry_deferred()
    bus.handle(0.1)
    assert len(replies) == 1 and ready["calls"] == 2
    server.retry_deferred()  # nothing left: not run again
    assert ready["calls"] == 2


def test_a_publication_from_a_tick_goes_out_with_the_next_frame():
    bus = open_bus("memq://")
    p = LockstepParticipant(bus, "proc")
    p.outbox.begin_frame(7, 70)
    with tick_context.ticking(7, 70):
        msg = test_sample_t()
        msg.text = "held"
        p.publish("SB_X", msg)
    assert p.outbox.counts == {}  # not in frame 7, whenever the tick came
    p.outbox.begin_frame(8, 80)
    p._publish_held(8)
    assert p.outbox.counts == {"SB_X": 1}
    outside = test_sample_t()
    p.publish("SB_X", outside)  # outside a tick: at once, in the current frame
    assert p.outbox.counts == {"SB_X": 2}
