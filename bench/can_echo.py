"""The far end of the raw frame ping-pong of bench/can_latency.py: answers every frame
with id 0x100 by the same bytes on id 0x101, until it receives id 0x7FF."""

import sys

import can

bus = can.Bus(interface=sys.argv[1], channel=sys.argv[2])
print("ready", flush=True)
while True:
    m = bus.recv(1.0)
    if m is None:
        continue
    if m.arbitration_id == 0x7FF:
        break
    if m.arbitration_id == 0x100:
        bus.send(can.Message(arbitration_id=0x101, data=m.data, is_extended_id=False))
bus.shutdown()
