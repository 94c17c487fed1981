"""The udpm:// bus read on the caller's thread (skillbus.bus.LcmBus): its two lanes are read
first in turn, so that a busy lane never starves the other, and a channel's lane is the
same at every publish (its name checked once), in a real network namespace."""

from __future__ import annotations

import json
import sys

from conftest import lcm_only

CODE = r'''
import json, time
from skillbus.bus import open_bus, BusError
bus = open_bus()
got = []
bus.subscribe("SB_T", lambda ch, d: got.append(d.decode()))
bus.subscribe("SB_T_ACK", lambda ch, d: got.append(d.decode()))
for text in ("a1", "a2", "a3"):
    bus.publish("SB_T", text.encode())          # lane 0
for text in ("b1", "b2", "b3"):
    bus.publish("SB_T_ACK", text.encode())      # lane 1 (port + 1)
time.sleep(0.3)  # (all six are in the two sockets' buffers)
for _ in range(6):
    assert bus.handle(1.0)
refused = ""
try:
    bus.publish("SB_" + "x" * 70, b"x")
except BusError as e:
    refused = str(e)
again = ""
try:
    bus.publish("SB_" + "x" * 70, b"x")  # (refused every time, not only the first)
except BusError as e:
    again = str(e)
print(json.dumps({"got": got, "refused": refused, "again": again}))
'''


@lcm_only("the two lanes are LCM's udpm:// sockets")
def test_the_two_lanes_are_read_first_in_turn_and_a_long_name_is_always_refused(sandbox):
    p = sandbox.start("lanes", [sys.executable, "-c", CODE], env={"SKILLBUS_KEY_FILE": "none"})
    assert sandbox.wait(p, 60) == 0, p.stderr()[-2000:]
    out = json.loads(p.stdout().strip().splitlines()[-1])
    # One message per handle(), the lane read first alternating: neither lane waits for
    # the other's backlog.
    assert out["got"] == ["a1", "b1", "a2", "b2", "a3", "b3"]
    assert "longer" in out["refused"] or "63" in out["refused"]
    assert out["again"] == out["refused"]
