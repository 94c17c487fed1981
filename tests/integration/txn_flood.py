"""Publishes COUNT signed SB_WM_TXN messages whose lockstep header is sound and whose
transaction is cut short (undecodable), as a faulty or hostile key holder would; prints
how many it sent. Used by test_log_flood.py.

    txn_flood.py COUNT
"""

import sys
import time

from skillbus.bus import channel, open_bus
from skillbus.msgs import wm_txn_t

count = int(sys.argv[1])
bus = open_bus()
for i in range(count):
    t = wm_txn_t()
    t.header.frame, t.header.sender, t.header.seq = 0, "flooder", i
    t.client_id, t.request_id, t.expected_version = "flooder", i + 1, -1
    data = t.encode()
    bus.publish(channel("SB_WM_TXN"), data[:-6])  # (the header intact, the rest cut short)
    if i % 200 == 199:
        time.sleep(0.02)  # (no kernel buffer overflow: every message should arrive)
print(count, flush=True)
