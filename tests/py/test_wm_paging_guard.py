"""A world model server whose pages do not advance by id (a bug, or another program on its
channels) fails the read naming it, instead of asking for the same page for ever: the
queries' pages (skillbus.world.wire.query_all) and a replica's snapshot
(WorldModelInterface._read_pages). The server is a stand-in here."""

from __future__ import annotations

import threading

from skillbus.msgs import wm_element_t, wm_elements_t, wm_query_t
from skillbus.world import client as wm_client
from skillbus.world.wire import PAGE, query_all


def page_of(ids: list[str], version: int = 1) -> wm_elements_t:
    out = wm_elements_t()
    out.elements = []
    for i in ids:
        e = wm_element_t()
        e.id = i
        out.elements.append(e)
    out.num_elements, out.version = len(ids), version
    return out


def returns_within(fn, limit: float = 20.0):
    out: dict = {}

    def run():
        try:
            out["r"] = fn()
        except Exception as e:  # noqa: BLE001
            out["e"] = e
    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(limit)
    assert not t.is_alive(), f"still reading pages after {limit} s"
    return out


def test_a_query_whose_pages_do_not_advance_fails_naming_it():
    same = [f"skiros:A-{i:04d}" for i in range(PAGE)]
    asked = []

    def call(req, timeout):
        asked.append(req.after)
        return page_of(same)  # (every page the same: it ignores `after`)

    out = returns_within(lambda: query_all(call, wm_query_t()))
    assert "does not page by id" in str(out.get("e")), out
    assert asked == ["", same[-1]]


def test_pages_that_advance_are_all_read():
    ids = [f"skiros:A-{i:04d}" for i in range(2 * PAGE + 3)]

    def call(req, timeout):
        rest = [i for i in ids if i > req.after]
        return page_of(rest[:req.limit])

    assert [e.id for e in query_all(call, wm_query_t())] == ids


def test_a_snapshot_whose_pages_do_not_advance_fails_the_replica_naming_it():
    wmi = wm_client.WorldModelInterface.__new__(wm_client.WorldModelInterface)
    same = [f"skiros:A-{i:04d}" for i in range(wm_client.WorldModelInterface.SNAPSHOT_PAGE)]
    wmi._call_elements = lambda method, q, timeout=None: page_of(same)
    out = returns_within(wmi._read_pages)
    assert isinstance(out.get("e"), wm_client.WorldModelError) and "does not page by id" in str(out["e"]), out
