"""On DDS, a reader that takes nothing (its process stopped, or killed and still matched
until its 3 s lease ends) makes a reliable writer wait: a write that times out is a lost
message, counted and logged as a refused send is on LCM, never an exception that kills
the sender (a client thread of the journal fault test died of it)."""

import json
import signal
import sys
import textwrap

from skillbus.waiting import wait_until

READER = textwrap.dedent('''
    import sys
    from skillbus.bus import open_raw_bus
    bus = open_raw_bus()
    def got(ch, d):
        if d == b"hello":
            print("got hello", flush=True)  # (so the writer has matched this reader)
    bus.subscribe("SB_TEST_SLOW", got)
    print("subscribed", flush=True)
    while True:
        bus.handle(1.0)
''')

WRITER = textwrap.dedent('''
    import json, os, sys, time
    from skillbus.bus import open_raw_bus
    bus = open_raw_bus()
    bus.publish("SB_TEST_SLOW", b"hello")  # (the writer exists: it matches the reader)
    print("writing", flush=True)
    while not os.path.exists(sys.argv[1]):  # (until the reader is stopped)
        time.sleep(0.01)
    t0 = time.monotonic()
    for i in range(3000):
        bus.publish("SB_TEST_SLOW", bytes(20000))
    print(json.dumps({"lost_sends": bus.lost_sends, "seconds": time.monotonic() - t0}), flush=True)
''')


def test_a_write_to_a_reader_that_takes_nothing_is_a_counted_loss(tmp_path):
    from skillbus.netns import Sandbox
    with Sandbox(log_dir=tmp_path / "logs", transport="dds") as box:
        reader = box.start("reader", [sys.executable, "-c", READER], env={"SKILLBUS_KEY_FILE": "none"})
        reader.wait_for("subscribed", 30, stream="stdout")
        go = tmp_path / "stopped"
        writer = box.start("writer", [sys.executable, "-c", WRITER, str(go)], env={"SKILLBUS_KEY_FILE": "none"})
        writer.wait_for("writing", 30, stream="stdout")
        reader.wait_for("got hello", 30, stream="stdout")  # (discovery: the writer has matched the reader)
        box.kill(reader, signal.SIGSTOP)  # (alive and matched, taking nothing)
        go.touch()
        wait_until(lambda: writer.popen.poll() is not None, 60, "the writer to finish")
        assert writer.popen.returncode == 0, writer.stderr()
        out = json.loads(writer.stdout().strip().splitlines()[-1])
        assert out["lost_sends"] >= 1, out
        assert out["seconds"] < 30, out  # (blocked a second at a time until the reader's lease ran out)
        assert "timed out: a reader takes nothing" in writer.stderr() and "message lost (#1)" in writer.stderr()
        box.kill(reader, signal.SIGCONT)
