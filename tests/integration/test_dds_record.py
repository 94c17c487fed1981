"""`skillbus dds-record`: an LCM log of a DDS domain. Every skillbus topic that appears,
found by discovery (also one that appears after the recorder started), is recorded in
order, with its bytes as sent, and the file reads as an LCM log. A topic that carried a
burst before the recorder found it keeps what its writer holds for late readers (the
last 16), a state channel's too."""

import sys
import textwrap

import lcm

from conftest import last_json
from skillbus.waiting import wait_until

WRITER = textwrap.dedent('''
    import sys, time
    from skillbus.bus import open_bus
    bus = open_bus()

    def matched():
        for channel in ("SB_TEST_A", "SB_TEST_B"):
            assert bus.wait_matched(channel, 30), "the recorder never read " + channel

    time.sleep(float(sys.argv[1]))  # (the recorder finds this participant meanwhile, or not: it must not matter)
    for i in range(50):
        bus.publish("SB_TEST_A", b"a%d" % i)
        if i % 5 == 0:
            bus.publish("SB_TEST_B", bytes(3000 + i))
        if i == 0 and sys.argv[1] != "0":
            # A topic exists from its first message on; the recorder finds it by discovery
            # and gets what its writer keeps for late readers (skillbus.dds): the last 16.
            # This writer waits for it before going on (the burst writer does not).
            matched()
        time.sleep(0.002)
    matched()
    time.sleep(1.0)  # (the burst's history, sent to the recorder that matched late: wait_acknowledged)
    assert bus.wait_acknowledged(30), "the recorder did not acknowledge everything"  # (it cannot be lost now)
''')

# 30 messages on a state channel at once, all written before the recorder can know the
# topic; then it stays while the recorder reads the topic: a writer that is gone cannot
# hand a reader that matched it late what it kept (being matched and acknowledged does
# not say the history was sent).
STATE_BURST = textwrap.dedent('''
    import time
    from skillbus.bus import open_bus
    bus = open_bus()
    for i in range(30):
        bus.publish("SB_TEST_F_STATE", b"s%d" % i)
    assert bus.wait_matched("SB_TEST_F_STATE", 30), "the recorder never read SB_TEST_F_STATE"
    time.sleep(2.0)
    assert bus.wait_acknowledged(30), "the recorder did not acknowledge everything"
''')


def test_every_topic_is_recorded_in_order_as_an_lcm_log(tmp_path):
    from skillbus.netns import Sandbox
    log = tmp_path / "run.lcmlog"
    with Sandbox(log_dir=tmp_path / "logs", transport="dds") as box:
        rec = box.start("rec", [sys.executable, "-m", "skillbus.cli", "dds-record", str(log)],
                        env={"SKILLBUS_KEY_FILE": "none"})
        early = box.start("early", [sys.executable, "-c", WRITER, "1.0"], env={"SKILLBUS_KEY_FILE": "none"})
        assert box.wait(early, 60) == 0, early.stderr()
        late = box.start("late", [sys.executable, "-c", WRITER.replace("SB_TEST_A", "SB_TEST_C"), "1.0"],
                         env={"SKILLBUS_KEY_FILE": "none"})
        burst = box.start("burst", [sys.executable, "-c", WRITER.replace("SB_TEST_A", "SB_TEST_D")
                                    .replace("SB_TEST_B", "SB_TEST_E"), "0"], env={"SKILLBUS_KEY_FILE": "none"})
        # the same burst on state channels, whose readers otherwise take nothing written
        # before they subscribed (skillbus.dds): the recorder takes their history too
        burst_state = box.start("burst_state", [sys.executable, "-c", STATE_BURST], env={"SKILLBUS_KEY_FILE": "none"})
        assert box.wait(late, 60) == 0, late.stderr()
        assert box.wait(burst, 60) == 0, burst.stderr()
        assert box.wait(burst_state, 60) == 0, burst_state.stderr()
        wait_until(lambda: log.stat().st_size > 0, 10, "the log to be written")
        box.kill(rec, 15)  # (SIGTERM: it closes the log and prints its summary)
        assert box.wait(rec, 20) == 0, rec.stderr()
        summary = last_json(rec.stdout())
    events = list(lcm.EventLog(str(log), "r"))
    by_channel: dict[str, list[bytes]] = {}
    for ev in events:
        by_channel.setdefault(ev.channel, []).append(bytes(ev.data))
    assert by_channel["SB_TEST_A"] == [b"a%d" % i for i in range(50)]
    assert by_channel["SB_TEST_C"] == [b"a%d" % i for i in range(50)]
    assert by_channel["SB_TEST_B"] == 2 * [bytes(3000 + i) for i in range(0, 50, 5)]
    burst = by_channel["SB_TEST_D"]  # written before the recorder could know the topic
    assert len(burst) >= 16 and burst == [b"a%d" % i for i in range(50 - len(burst), 50)], burst
    state = by_channel["SB_TEST_F_STATE"]  # the last 16 of 30 at least (more when it found the topic early)
    assert len(state) >= 16 and state == [b"s%d" % i for i in range(30 - len(state), 30)], state
    assert summary["events"] == len(events) and summary["channels"] == 6
    assert [ev.eventnum for ev in events] == list(range(len(events)))
    assert all(a.timestamp <= b.timestamp + 1000 for a, b in zip(events, events[1:]))


def test_it_refuses_a_bus_that_is_not_dds(tmp_path):
    import subprocess
    r = subprocess.run([sys.executable, "-m", "skillbus.cli", "dds-record", str(tmp_path / "x.lcmlog"),
                        "--url", "udpm://239.255.76.67:7667?ttl=0"], capture_output=True, text=True, timeout=30)
    assert r.returncode == 2 and "records a DDS domain" in r.stderr and "skillbus record" in r.stderr


def test_waiting_for_a_reader_that_is_not_there_ends_at_its_timeout(tmp_path):
    from skillbus.netns import Sandbox
    code = textwrap.dedent('''
        import time
        from skillbus.bus import open_raw_bus
        bus = open_raw_bus()
        bus.publish("SB_TEST_NOBODY", b"x")
        t0 = time.monotonic()
        assert not bus.wait_matched("SB_TEST_NOBODY", 0.3)  # (no reader of it in the domain)
        assert not bus.wait_matched("SB_TEST_NEVER_SENT", 0.1)  # (no writer of it in this process)
        assert 0.4 <= time.monotonic() - t0 < 5
        assert bus.wait_acknowledged(1)  # (nobody to wait for)
        print("ok", flush=True)
    ''')
    with Sandbox(log_dir=tmp_path / "logs", transport="dds") as box:
        p = box.start("w", [sys.executable, "-c", code], env={"SKILLBUS_KEY_FILE": "none"})
        assert box.wait(p, 60) == 0, p.stderr()
        assert "ok" in p.stdout()
