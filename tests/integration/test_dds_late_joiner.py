"""On DDS a reader that comes later starts from what is written after it subscribed on a
state channel (names ending in _STATE, _OBJECTS, _ARTICULATION), as on LCM, and from the
recent history its writers keep for late joiners on the others (what discovery delayed;
docs/transport.md, "DDS"). Before, a state reader got up to 2 s of old states first: a
probe reading the physics' state under lockstep saw the arm where it had been before its
last move, and four manipulation tests failed under `make test-dds`. Readers in Python
and in C++ (tests/cpp/bus_first_peer.cpp)."""

import json
import struct
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

# A reader that comes 2 s later: the first message it reads on CHANNEL, as the C++ peer
# prints it.
PY_READER = textwrap.dedent('''
    import json, sys, time
    from skillbus.bus import open_bus
    bus = open_bus()
    first = []
    subscribed = time.time_ns()
    bus.subscribe(sys.argv[1], lambda ch, d: first.append(d[:16].hex()) if not first else None)
    end = time.monotonic() + 10
    while not first and time.monotonic() < end:
        bus.handle(0.05)
    print(json.dumps({"subscribed_ns": subscribed, "first": first[0] if first else ""}))
''')


def first_read(box, name: str, argv: list[str]) -> float:
    """How long before the reader subscribed its first message was written, in ms
    (negative: after)."""
    p = box.start(name, argv)
    assert box.wait(p, 30) == 0, p.stdout() + p.stderr()
    r = json.loads(p.stdout().strip().splitlines()[-1])
    _, written_ns = struct.unpack(">qq", bytes.fromhex(r["first"]))
    return (r["subscribed_ns"] - written_ns) / 1e6


@pytest.mark.parametrize("reader", ["python", "cpp"])
def test_a_late_state_reader_starts_from_what_comes_after_it(tmp_path, binary, reader):
    with Sandbox(log_dir=tmp_path / "logs", transport="dds") as box:
        writer = box.start("writer", [sys.executable, "-c", WRITER])
        time.sleep(2.0)  # (well inside the writer's 6 s, with 2 s of history behind)
        ages = {}
        for channel in ("SB_TEST_STATE", "SB_TEST_EVENTS"):
            argv = ([sys.executable, "-c", PY_READER, channel] if reader == "python"
                    else [str(binary("bus_first_peer")), channel])
            ages[channel] = first_read(box, f"{reader}-{channel}", argv)
        assert writer.popen.poll() is None, "the writer ended before the readers came"
    assert ages["SB_TEST_STATE"] <= 0, ages  # nothing older than the reader
    # the other channels keep the writer's recent history for late joiners (at 500 a
    # second, its last 16 span about 30 ms)
    assert 0 < ages["SB_TEST_EVENTS"] < 2000, ages
