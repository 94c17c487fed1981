"""Each udpm:// socket carries a kernel filter (common/include/skillbus/channel_filter.hpp):
a short LCM message of a channel the process did not subscribe to is dropped before it
wakes the process; everything else still reaches the reader, which counts what is bad.
In Python the filter comes from skillbus_native; without it every datagram is read, as
before. (The filter's program itself: tests/cpp/test_channel_filter.cpp.)"""

from __future__ import annotations

import os
import sys
import textwrap
from pathlib import Path

from skillbus.netns import last_json
from skillbus.paths import binary
from conftest import lcm_only

NO_KEY = {"SKILLBUS_KEY_FILE": "none"}

# A bus subscribed to SB_WANTED; LCM's own publisher then sends other channels, a
# malformed short message and SB_WANTED. What the kernel queued on the bus's socket is
# read straight from a duplicate of it, in order, before the bus's reader sees anything.
SCRIPT = textwrap.dedent("""
    import json, os, select, socket, sys, time
    import lcm
    from skillbus.bus import LcmBus, resolve_url, udpm_address
    bus = LcmBus(resolve_url())
    sid = bus.subscribe("SB_WANTED", lambda ch, d: None)
    raw = lcm.LCM(resolve_url())
    group, port, _ = udpm_address(resolve_url())
    junk = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    junk.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
    sock = socket.socket(fileno=os.dup(bus.lane0_socket()))
    sock.setblocking(False)

    def queued(last):
        out = []
        end = time.monotonic() + 5
        while time.monotonic() < end:
            if not select.select([sock], [], [], 0.2)[0]:
                continue
            d = sock.recv(70000)
            out.append(d[8:d.index(b"\\0", 8)].decode() if d[:4] == b"LC02" and b"\\0" in d[8:] else d[:4].decode())
            if out[-1] == last:
                return out
        return out

    for ch in ("SB_OTHER", "SB_WANTED_NOT", "SB_WANTE"):
        raw.publish(ch, b"x")
    junk.sendto(b"LC02" + bytes(4) + b"SB_NO_NUL", (group, port))
    raw.publish("SB_WANTED", b"x")
    first = queued("SB_WANTED")
    bus.subscribe("SB_LATER", lambda ch, d: None)   # a new subscription passes at once
    bus.unsubscribe(sid)                            # and an ended one no longer does
    raw.publish("SB_WANTED", b"x")
    raw.publish("SB_LATER", b"x")
    then = queued("SB_LATER")
    print(json.dumps({"first": first, "then": then}))
""")


@lcm_only("the kernel filter of a udpm:// socket")
def test_the_kernel_drops_messages_of_channels_the_process_did_not_subscribe_to(sandbox):
    p = sandbox.start("py", [sys.executable, "-c", SCRIPT], env=NO_KEY)
    assert sandbox.wait(p, 60) == 0, p.stderr()
    r = last_json(p.stdout())
    assert r["first"] == ["LC02", "SB_WANTED"], r  # (the malformed one, for the reader to count)
    assert r["then"] == ["SB_LATER"], r


@lcm_only("the kernel filter of a udpm:// socket")
def test_without_the_native_module_every_datagram_reaches_the_reader(sandbox):
    p = sandbox.start("py", [sys.executable, "-c", SCRIPT], env={**NO_KEY, "SKILLBUS_NATIVE": "0"})
    assert sandbox.wait(p, 60) == 0, p.stderr()
    r = last_json(p.stdout())
    assert r["first"] == ["SB_OTHER", "SB_WANTED_NOT", "SB_WANTE", "LC02", "SB_WANTED"], r
    assert r["then"] == ["SB_WANTED", "SB_LATER"], r


# Other channels, then the one the C++ echo subscribed to; waits for its echo.
PUBLISHER = textwrap.dedent("""
    import sys, time
    import lcm
    from skillbus.bus import LcmBus, resolve_url
    bus = LcmBus(resolve_url())
    got = []
    bus.subscribe("SB_ECHO_OUT", lambda ch, d: got.append(d))
    raw = lcm.LCM(resolve_url())
    for i in range(int(sys.argv[1])):
        raw.publish("SB_NOT_FOR_THE_ECHO", b"x")
    raw.publish("SB_ECHO_IN", b"hello")
    end = time.monotonic() + 10
    while not got and time.monotonic() < end:
        bus.handle(0.05)
    print("echoed" if got == [b"hello"] else f"no echo: {got}", flush=True)
""")


def socket_drops(pid: int) -> int:
    """Datagrams the kernel dropped on process `pid`'s UDP sockets (the filter's drops are
    counted there), from its network namespace's /proc/net/udp."""
    inodes = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            target = os.readlink(fd)
        except OSError:
            continue
        if target.startswith("socket:["):
            inodes.add(target[8:-1])
    drops = 0
    for line in Path(f"/proc/{pid}/net/udp").read_text().splitlines()[1:]:
        f = line.split()
        if f[9] in inodes:
            drops += int(f[12])
    return drops


@lcm_only("the kernel filter of a udpm:// socket")
def test_a_cpp_process_is_not_woken_by_channels_it_did_not_subscribe_to(sandbox):
    echo = sandbox.start("echo", [binary("codec_peer"), "--echo", "30"], env=NO_KEY)
    echo.wait_for("ready", 20, stream="stdout")
    before = socket_drops(echo.popen.pid)
    p = sandbox.start("py", [sys.executable, "-c", PUBLISHER, "25"], env=NO_KEY)
    assert sandbox.wait(p, 60) == 0, p.stderr()
    assert p.stdout().strip() == "echoed", p.stdout()
    # The 25, and its own echo (multicast loops back; it did not subscribe to SB_ECHO_OUT).
    assert socket_drops(echo.popen.pid) - before == 26
