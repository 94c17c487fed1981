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
