"""skillbus.startup_heap: what a process built before serving is set aside from the cyclic
collector's walks; what it makes afterwards is still collected. Each case runs in its own
interpreter: freezing is for the whole process."""

import json
import subprocess
import sys

PROBE = r'''
import gc, json, time
from skillbus import startup_heap

class Node:
    def __init__(self):
        self.me = self  # a cycle: only the cyclic collector frees it

built = [{"n": i, "list": [i]} for i in range(200_000)]   # a large start-up heap
t = time.perf_counter(); gc.collect(); before_ms = (time.perf_counter() - t) * 1e3
count = startup_heap.set_aside()
t = time.perf_counter(); gc.collect(); after_ms = (time.perf_counter() - t) * 1e3
old_walked = any(o is built for o in gc.get_objects())   # (the collector's generations only)
import weakref
later = Node(); ref = weakref.ref(later); del later
gc.collect()
print(json.dumps({"count": count, "again": startup_heap.set_aside() >= count, "before_ms": before_ms,
                  "after_ms": after_ms, "old_walked": old_walked, "later_freed": ref() is None}))
'''


def test_start_up_objects_leave_the_collectors_walks_and_later_cycles_are_still_freed():
    out = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["count"] > 400_000  # the dicts and lists built before
    assert got["again"]
    assert not got["old_walked"]
    assert got["later_freed"]  # a cycle made after set_aside is still collected
    # A full collection no longer walks the start-up heap: far cheaper than before.
    assert got["after_ms"] < got["before_ms"] / 5, got


RELEASE = r'''
import gc, json, weakref
from skillbus import startup_heap

class Node:
    def __init__(self):
        self.me = self

old = Node(); ref = weakref.ref(old)
startup_heap.set_aside()
del old
gc.collect()
kept_while_frozen = ref() is not None   # a frozen cycle is not walked
released = startup_heap.release()
gc.collect()
print(json.dumps({"kept": kept_while_frozen, "released": released, "freed": ref() is None,
                  "count": gc.get_freeze_count(), "again": startup_heap.release()}))
'''


def test_released_objects_are_collected_again():
    out = subprocess.run([sys.executable, "-c", RELEASE], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    got = json.loads(out.stdout.strip().splitlines()[-1])
    assert got["kept"] and got["released"] > 0
    assert got["freed"] and got["count"] == 0 and got["again"] == 0


def test_a_replica_read_again_gives_the_old_one_back_to_the_collector(monkeypatch):
    # The skill process's replica is part of its set-aside start-up heap; a resync drops it.
    from skillbus import startup_heap
    from skillbus.bus import open_bus
    from skillbus.world.client import WorldModelInterface

    real_resync = WorldModelInterface.resync
    monkeypatch.setattr(WorldModelInterface, "resync", lambda self: None)
    w = WorldModelInterface(open_bus("memq://"), "test")
    released, set_aside = [], []
    frozen = [0]
    monkeypatch.setattr(startup_heap, "release", lambda: released.append(True) or frozen[0])
    monkeypatch.setattr(startup_heap, "set_aside", lambda: set_aside.append(True) or 1)
    monkeypatch.setattr(WorldModelInterface, "_read_pages", lambda self: ({}, [], 7, 7))
    monkeypatch.setattr(WorldModelInterface, "_changes_up_to", lambda self, first, last: [])
    real_resync(w)  # nothing was set aside: nothing is set aside after
    assert released == [True] and set_aside == [] and w.version == 7
    frozen[0] = 120_000  # a serving process: the new replica is set aside again
    real_resync(w)
    assert released == [True, True] and set_aside == [True]
