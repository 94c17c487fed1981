"""The bus reads udpm:// on the dispatching thread (skillbus.udpm, common/src/udpm_receiver.cpp)
in LCM's wire format: what LCM itself publishes, fragmented or not, arrives whole in
Python and in C++, and what does not parse is counted and dropped without harm."""

from __future__ import annotations

import json
import sys
import textwrap

from skillbus.netns import last_json
from skillbus.paths import binary
from conftest import lcm_only

NO_KEY = {"SKILLBUS_KEY_FILE": "none"}
# One datagram, one just under LCM's limit for one, fragmented ones up to 4 MB.
SIZES = [0, 1, 1400, 65_000, 65_487, 65_500, 300_000, 4_000_000]

# LCM's own library publishes (lcm.LCM: fragments what is over one datagram); the
# skillbus bus in this process and the C++ echo both receive; the bus then also takes the
# echo, which the C++ bus published (through LCM again).
SCRIPT = textwrap.dedent("""
    import json, random, sys, time
    import lcm
    from skillbus.bus import LcmBus, resolve_url
    sizes = json.loads(sys.argv[1])
    rng = random.Random(7)
    sent = [rng.randbytes(n) for n in sizes]
    bus = LcmBus(resolve_url())
    direct, echoed = [], []
    bus.subscribe("SB_ECHO_IN", lambda ch, d: direct.append(d))
    bus.subscribe("SB_ECHO_OUT", lambda ch, d: echoed.append(d))
    raw = lcm.LCM(resolve_url())
    for d in sent:
        raw.publish("SB_ECHO_IN", d)
        end = time.monotonic() + 10
        while (len(direct) < len(sent[:sent.index(d) + 1]) or len(echoed) < len(direct)) and time.monotonic() < end:
            bus.handle(0.05)
    print(json.dumps({"direct": [a == b for a, b in zip(direct, sent)], "echoed": [a == b for a, b in zip(echoed, sent)],
                      "counts": [len(direct), len(echoed)], "undecodable": bus.undecodable}))
""")


@lcm_only("LCM's wire format on udpm://")
def test_messages_of_every_size_arrive_whole_in_python_and_in_cpp(sandbox):
    echo = sandbox.start("echo", [binary("codec_peer"), "--echo", "60"], env=NO_KEY)
    echo.wait_for("ready", 20, stream="stdout")
    p = sandbox.start("py", [sys.executable, "-c", SCRIPT, json.dumps(SIZES)], env=NO_KEY)
    assert sandbox.wait(p, 60) == 0, p.stderr()
    r = last_json(p.stdout())
    assert r["counts"] == [len(SIZES), len(SIZES)], r
    assert all(r["direct"]) and all(r["echoed"]), r
    assert r["undecodable"] == 0


# Datagrams no LCM publisher sends, straight onto the group; then a good message.
GARBAGE = textwrap.dedent("""
    import socket, struct, sys, time
    from skillbus.bus import udpm_address, resolve_url
    group, port, _ = udpm_address(resolve_url())
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
    long = lambda seq, size, off, no, n: b"LC03" + struct.pack(">IIIHH", seq, size, off, no, n)
    bad = [b"", b"LC0", b"LC02", b"LC02" + bytes(4) + b"SB_ECHO_IN",  # no NUL after the channel
           b"LC02" + bytes(4) + b"\\0payload",                          # no channel
           b"LC02" + bytes(4) + b"A" * 200 + b"\\0x",                  # channel too long
           b"XXXX" + bytes(40),
           long(1, 10, 0, 0, 0) + b"SB_ECHO_IN\\0x",                 # no fragments
           long(2, 10, 0, 3, 2) + b"x",                              # fragment 3 of 2
           long(3, 10, 8, 1, 2) + b"xxxxxxxxxx",                     # past the end
           long(4, 1 << 30, 0, 0, 2) + b"SB_ECHO_IN\\0x",            # a gigabyte
           long(5, 20, 0, 0, 2) + b"SB_ECHO_IN\\0" + b"a" * 10,      # first half only, then:
           long(6, 20, 0, 0, 2) + b"SB_ECHO_IN\\0" + b"b" * 10,      # another message (5 lost a part)
           long(6, 20, 10, 1, 2) + b"c" * 10]                        # which completes
    for d in bad:
        s.sendto(d, (group, port))
    print("sent", flush=True)
""")

RECEIVER = textwrap.dedent("""
    import json
    from skillbus.bus import LcmBus, resolve_url
    from skillbus.waiting import poll_until
    bus = LcmBus(resolve_url())
    got = []
    bus.subscribe("SB_ECHO_IN", lambda ch, d: got.append(d))
    bus.subscribe("SB_ECHO_OUT", lambda ch, d: got.append(b"echo:" + d))
    print("ready", flush=True)
    # Until the good message and its echo are here (the bad datagrams came before them, on
    # the same socket), then a while more: anything else that came would be counted too.
    poll_until(lambda: len(got) >= 2, 30, step=bus.handle)
    while bus.handle(0.5):
        pass
    print(json.dumps({"got": [g.decode() for g in got], "undecodable": bus.undecodable}))
""")


@lcm_only("LCM's wire format on udpm://")
def test_datagrams_that_are_no_lcm_message_are_counted_and_dropped(sandbox):
    echo = sandbox.start("echo", [binary("codec_peer"), "--echo", "30"], env=NO_KEY)
    echo.wait_for("ready", 20, stream="stdout")
    rx = sandbox.start("rx", [sys.executable, "-c", RECEIVER], env=NO_KEY)
    rx.wait_for("ready", 20, stream="stdout")
    tx = sandbox.start("tx", [sys.executable, "-c", GARBAGE], env=NO_KEY)
    assert sandbox.wait(tx, 20) == 0, tx.stderr()
    assert sandbox.wait(rx, 30) == 0, rx.stderr()
    r = last_json(rx.stdout())
    # Only the one good message, directly and echoed by C++ (which survived the rest).
    assert sorted(r["got"]) == ["b" * 10 + "c" * 10, "echo:" + "b" * 10 + "c" * 10], r
    assert r["undecodable"] == 12, r  # 11 that do not parse, 1 message that lost a fragment
