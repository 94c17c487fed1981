"""A recorder told to stop (SIGTERM, SIGINT, --seconds) first writes what has reached it:
the messages waiting in its socket buffers (LCM) or reader queues (DDS). On DDS their
writers already hold the recorder's acknowledgement and never send them again, so a
stop between their arrival and their reading lost them (skillbus.record.record_until)."""

import sys
import textwrap

from conftest import last_json

RECORD_THEN_STOP = textwrap.dedent('''
    import json, sys
    from skillbus.bus import open_raw_bus, resolve_url
    from skillbus.record import open_recorder, record_until
    from skillbus.waiting import wait_until

    rec = open_recorder(resolve_url(None), sys.argv[1])
    bus = open_raw_bus()
    bus.publish("SB_TEST_Q", b"q0")  # (on DDS the topic exists from here on: the recorder finds it)
    wait_until(lambda: rec.log.events >= 1, 30, "the recorder's q0", interval=0.01, step=rec.spin)
    for i in range(1, 20):
        bus.publish("SB_TEST_Q", b"q%d" % i)
    if hasattr(bus, "wait_acknowledged"):  # (DDS: until the recorder has them all)
        assert bus.wait_acknowledged(30), "not acknowledged"
    # (LCM on loopback: a datagram is in every member's socket buffer when its send returns)
    print(json.dumps({"events": record_until(rec, lambda: True)}), flush=True)
''')


def test_what_reached_the_recorder_before_its_stop_is_recorded(transport_sandbox, tmp_path):
    import lcm
    box = transport_sandbox
    log = tmp_path / "stop.lcmlog"
    p = box.start("rec", [sys.executable, "-c", RECORD_THEN_STOP, str(log)], env={"SKILLBUS_KEY_FILE": "none"})
    assert box.wait(p, 60) == 0, p.stderr()
    data = [bytes(e.data) for e in lcm.EventLog(str(log), "r") if e.channel == "SB_TEST_Q"]
    assert data == [b"q%d" % i for i in range(20)]
    assert last_json(p.stdout())["events"] == len(data)
