"""On DDS a reader that comes later starts from what is written after it subscribed on a
state channel (names ending in _STATE, _OBJECTS, _ARTICULATION), as on LCM; on the others
it may also get the recent history its writers keep for late joiners (docs/transport.md,
"DDS"). Before, a state reader got up to 2 s of old states first: a
probe reading the physics' state under lockstep saw the arm where it had been before its
last move, and four manipulation tests failed under `make test-dds`. Readers in Python
and in C++ (tests/cpp/bus_late_reader_peer.cpp)."""

import json
import sys
import textwrap
import time

import pytest

from skillbus.netns import Sandbox

# Writes (index, wall clock ns) on both channels, 500 a second, for 6 s.
WRITER = textwrap.dedent('''
    import struct, time
    from skillbus.bus import open_bus
    bus = open_bus()
    for i in range(3000):
        for channel in ("SB_TEST_STATE", "SB_TEST_EVENTS"):
            bus.publish(channel, struct.pack(">qq", i, time.time_ns()))
        time.sleep(0.002)
''')

# A reader that comes 2 s later, as the C++ peer: the earliest writer's time among what
# it reads in 0.5 s from its first message.
PY_READER = textwrap.dedent('''
    import json, struct, sys, time
    from skillbus.bus import open_bus
    bus = open_bus()
    times = []
    subscribed = time.time_ns()
    bus.subscribe(sys.argv[1], lambda ch, d: times.append(struct.unpack(">qq", d[:16])[1]))
    give_up = time.monotonic() + 10
    while not times and time.monotonic() < give_up:
        bus.handle(0.05)
    end = time.monotonic() + 0.5
    while times and time.monotonic() < end:
        bus.handle(0.02)
    print(json.dumps({"subscribed_ns": subscribed, "earliest_ns": min(times, default=0), "read": len(times)}))
''')


def oldest_read(box, name: str, argv: list[str]) -> float:
    """How long before the reader subscribed the oldest message it read was written, in ms
    (negative: after)."""
    p = box.start(name, argv)
    assert box.wait(p, 30) == 0, p.stdout() + p.stderr()
    r = json.loads(p.stdout().strip().splitlines()[-1])
    assert r["read"] > 0, r
    return (r["subscribed_ns"] - r["earliest_ns"]) / 1e6


@pytest.mark.parametrize("reader", ["python", "cpp"])
def test_a_late_state_reader_starts_from_what_comes_after_it(tmp_path, binary, reader):
    with Sandbox(log_dir=tmp_path / "logs", transport="dds") as box:
        writer = box.start("writer", [sys.executable, "-c", WRITER])
        time.sleep(2.0)  # (well inside the writer's 6 s, with 2 s of history behind)
        ages = {}
        for channel in ("SB_TEST_STATE", "SB_TEST_EVENTS"):
            argv = ([sys.executable, "-c", PY_READER, channel] if reader == "python"
                    else [str(binary("bus_late_reader_peer")), channel])
            ages[channel] = oldest_read(box, f"{reader}-{channel}", argv)
        assert writer.popen.poll() is None, "the writer ended before the readers came"
    assert ages["SB_TEST_STATE"] <= 0, ages  # nothing older than the reader
    # (the other channels may hand it what their writers kept for late joiners: at 500 a
    # second, the last 16 span about 30 ms; Cyclone does not always send it at once)
    assert ages["SB_TEST_EVENTS"] < 2000, ages
