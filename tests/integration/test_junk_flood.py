"""A flood of datagrams that no reader can use (short messages whose channel never ends: the
kernel's channel filter lets them through, the readers count and drop them) holds no
process past its timeouts: a C++ lockstep master still names a participant that never
joined, a Python participant still names the master that never came. The readers look at
the time every 256 such datagrams (LcmBus::handle_direct, skillbus.bus.LcmBus); on this
machine both also outpace one Python flooder, so the failures before that change are
tests/py/test_bus_junk_flood.py's, with a reader that never runs dry."""

import json
import sys
import textwrap
import time

from conftest import last_json, lcm_only
from skillbus.lockstep_session import python_participant_argv

FLOOD = textwrap.dedent('''
    import socket
    from skillbus.bus import lane1_url, resolve_url, udpm_address
    url = resolve_url(None)
    lanes = [udpm_address(u)[:2] for u in (url, lane1_url(url))]  # (the clocks' lane; the acks' and joins')
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
    junk = b"LC02" + bytes(4) + b"SB_NO_NUL" * 20  # a short message whose channel never ends
    while True:
        for lane in lanes:
            s.sendto(junk, lane)
''')


# A reader on the bus for half a second: how many undecodable datagrams reached it (the
# flood is on, and past the kernel's channel filter).
COUNT = textwrap.dedent('''
    import time
    from skillbus.bus import LcmBus, resolve_url
    bus = LcmBus(resolve_url(None))
    bus.subscribe("SB_NOTHING", lambda ch, d: None)
    end = time.monotonic() + 0.5
    while time.monotonic() < end:
        bus.handle(0.05)
    print(bus.undecodable)
''')


def flooding(sandbox):
    floods = [sandbox.start(f"flood{i}", [sys.executable, "-c", FLOOD]) for i in range(2)]
    counter = sandbox.start("count", [sys.executable, "-c", COUNT], env={"SKILLBUS_KEY_FILE": "none"})
    assert sandbox.wait(counter, 30) == 0, counter.stderr()
    assert int(counter.stdout().split()[-1]) > 1000, counter.stdout()
    return floods


@lcm_only("udpm:// datagrams that are no LCM message")
def test_a_cpp_master_names_who_never_joined_during_a_flood(sandbox, binary):
    floods = flooding(sandbox)
    t0 = time.monotonic()
    clock = sandbox.start("clock", [binary("sb_clock"), "--participants", "ghost", "--frames", "10",
                                    "--join-timeout-ms", "1500"])
    try:
        assert sandbox.wait(clock, 30) == 1, clock.stderr()
    finally:
        for f in floods:
            sandbox.kill(f)
    assert "participant(s) ghost never joined within 1.5 s" in last_json(clock.stdout())["error"]
    assert time.monotonic() - t0 < 15


@lcm_only("udpm:// datagrams that are no LCM message")
def test_a_python_participant_names_the_missing_master_during_a_flood(sandbox):
    floods = flooding(sandbox)
    t0 = time.monotonic()
    part = sandbox.start("py1", python_participant_argv("py1", "--clock-timeout", "1.5"))
    try:
        sandbox.wait(part, 30)
    finally:
        for f in floods:
            sandbox.kill(f)
    out = last_json(part.stdout()) or {}
    assert "no clock from the master" in json.dumps(out) + part.stderr(), (out, part.stderr()[-2000:])
    assert time.monotonic() - t0 < 15


@lcm_only("udpm:// datagrams that are no LCM message")
def test_a_lockstep_session_during_a_flood_loses_nothing(sandbox, tmp_path):
    """Every clock, ack and stamped message still reaches its reader among the junk: the
    C++ master and participant and the Python participants end with the digests of a run
    without the flood."""
    from skillbus.lockstep_session import run_session
    from skillbus.netns import Sandbox
    with Sandbox(log_dir=tmp_path / "clean") as box:
        clean = run_session(box, frames=1000, n_python=2, n_cpp=1, timeout=120)
    assert clean["ok"], clean
    floods = flooding(sandbox)
    try:
        flooded = run_session(sandbox, frames=1000, n_python=2, n_cpp=1, timeout=180)
    finally:
        for f in floods:
            sandbox.kill(f)
    assert flooded["ok"] and flooded["frames"] == 1000, flooded
    assert flooded["digest"] == clean["digest"]
    for name, r in flooded["participant_results"].items():
        assert r["ok"] and r["digest"] == clean["participant_results"][name]["digest"], (name, r)


# 255 datagrams that dispatch nothing, then one message the reader wants, all queued in
# its socket before it reads: the message is its 256th read, where it looks at the time
# (past at once for handle(0)). Python's reader in-process, the C++ one in bus_junk_peer.
QUEUE_JUNK_THEN_WANTED = textwrap.dedent('''
    import socket, sys
    from skillbus.bus import resolve_url, udpm_address
    group, port, _ = udpm_address(resolve_url(None))
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
    for _ in range(255):
        s.sendto(b"LC02" + bytes(4) + b"SB_NO_NUL" * 20, (group, port))
    s.sendto(b"LC02" + bytes(4) + b"SB_WANTED\\0" + b"m", (group, port))
    if len(sys.argv) > 1:
        open(sys.argv[1], "w").close()
''')

PY_READER = textwrap.dedent('''
    import json, subprocess, sys
    from skillbus.bus import LcmBus, resolve_url
    bus = LcmBus(resolve_url(None))
    got = []
    bus.subscribe("SB_WANTED", lambda ch, d: got.append(d))
    subprocess.run([sys.executable, "-c", sys.argv[1]], check=True)
    while bus.handle(0.0):
        pass
    print(json.dumps({"got": len(got)}))
''')


@lcm_only("udpm:// datagrams that are no LCM message")
def test_a_wanted_message_behind_255_junk_datagrams_is_delivered(sandbox, binary, tmp_path):
    env = {"SKILLBUS_KEY_FILE": "none"}
    flag = tmp_path / "queued"
    cpp = sandbox.start("cpp", [binary("bus_junk_peer"), str(flag)], env=env)
    cpp.wait_for("ready", 30, stream="stdout")
    queue = sandbox.start("queue", [sys.executable, "-c", QUEUE_JUNK_THEN_WANTED, str(flag)], env=env)
    assert sandbox.wait(queue, 30) == 0, queue.stderr()
    assert sandbox.wait(cpp, 60) == 0, cpp.stderr()
    assert last_json(cpp.stdout()) == {"got": 1}
    py = sandbox.start("py", [sys.executable, "-c", PY_READER, QUEUE_JUNK_THEN_WANTED], env=env)
    assert sandbox.wait(py, 60) == 0, py.stderr()
    assert last_json(py.stdout()) == {"got": 1}
