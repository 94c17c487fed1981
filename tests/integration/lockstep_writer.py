"""A lockstep participant that adds one element (labelled argv[1]) to the world model in
its first frame and then follows the clock: the writer of test_wm_faults.py, run once,
killed, and run again as a restarted participant would be."""

import sys

from skillbus.bus import open_bus
from skillbus.lockstep import LockstepParticipant
from skillbus.msgs import wm_op_t
from skillbus.world import Element, WorldModelInterface
from skillbus.world.convert import op

label = sys.argv[1]
bus = open_bus()
participant = LockstepParticipant(bus, "writer", kind="test")
wmi = WorldModelInterface(bus, "writer", participant=participant)
print(f"first request id {wmi._txn_ids + 1}", file=sys.stderr, flush=True)
sent = []


def on_frame(frame, sim_time_ns):
    if not sent:
        sent.append(wmi.commit_async([op(wm_op_t.ADD_ELEMENT, element=Element("skiros:Cube", label))]))


participant.on_frame = on_frame
r = participant.run()
print(f"results {[(k, v.error, list(v.ids)) for k, v in sorted(wmi.results.items())]}", file=sys.stderr, flush=True)
