"""`skillbus record` told to stop while publishers flood the bus as fast as they can: it
stops within its drain time (skillbus.record.DRAIN_S) and leaves a whole log. On this
machine the recorder keeps up with two Python publishers, so this is the real processes'
check; a bus that never runs dry (where the recorder used to write for ever and never see
its stop) is in tests/py/test_record_drain.py."""

import signal
import sys
import textwrap

import lcm

from conftest import last_json
from skillbus.record import DRAIN_S

FLOOD = textwrap.dedent('''
    from skillbus.bus import open_raw_bus
    bus = open_raw_bus()
    i = 0
    while True:
        bus.publish("SB_TEST_FLOOD", b"f%09d" % i + bytes(100))
        i += 1
''')


FLOODERS = 2  # (publishing as fast as they can; here the recorder keeps up with them)


def test_a_stop_during_a_flood_ends_within_the_drain_time_with_a_whole_log(transport_sandbox, tmp_path):
    box = transport_sandbox
    log = tmp_path / "flood.lcmlog"
    env = {"SKILLBUS_KEY_FILE": "none"}
    rec = box.start("rec", [sys.executable, "-m", "skillbus.cli", "record", str(log)], env=env)
    rec.wait_for("recording", 30)
    floods = [box.start(f"flood{i}", [sys.executable, "-c", FLOOD], env=env) for i in range(FLOODERS)]
    box.start("mark", [sys.executable, "-c", f"from skillbus.monitor import mark_log; mark_log({str(log)!r}, timeout=30)"],
              env=env)
    box.wait(box.procs[-1], 60)  # (the recorder writes: it has found the bus, and on DDS the topics)
    box.kill(rec, signal.SIGTERM)
    try:
        assert box.wait(rec, DRAIN_S + 15) == 0, rec.stderr()
    finally:
        for f in floods:
            box.kill(f)
    summary = last_json(rec.stdout())
    events = list(lcm.EventLog(str(log), "r"))  # (the whole file reads: no event cut short)
    assert summary is not None and summary["events"] == len(events) > 0, (summary, len(events))
    flooded = [bytes(e.data) for e in events if e.channel == "SB_TEST_FLOOD"]
    assert flooded and all(d.startswith(b"f") and len(d) == 110 for d in flooded)
