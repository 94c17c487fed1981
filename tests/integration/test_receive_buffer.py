"""Every LCM socket asks for a large receive buffer (skillbus.bus.RECEIVE_BUFFER, capped by
net.core.rmem_max): a burst of 2 MB that arrives while a process is not scheduled (here:
stopped with SIGSTOP, as a loaded machine does for a moment) is kept by the kernel until
it reads it. The same burst into a socket with the kernel's default buffer (the URL
names it, as the default was before) loses most of it: the test can tell."""

from __future__ import annotations

import signal
import sys
import textwrap

from skillbus.bus import RECEIVE_BUFFER, kernel_receive_buffer_cap
from conftest import lcm_only

COUNT, SIZE = 40, 50_000  # 2 MB: ten times the kernel's default buffer

RECEIVER = textwrap.dedent("""
    import sys, time
    from skillbus.bus import open_bus, DEFAULT_URL
    url = sys.argv[1] or DEFAULT_URL
    bus = open_bus(url)
    got = []
    bus.subscribe("SB_BURST", lambda ch, data: got.append(len(data)))
    print("ready", flush=True)
    end = time.monotonic() + 2.0
    while time.monotonic() < end:
        bus.handle(0.05)
    print("got", len(got), flush=True)
""")

SENDER = textwrap.dedent(f"""
    from skillbus.bus import open_bus
    bus = open_bus()
    for i in range({COUNT}):
        bus.publish("SB_BURST", bytes([i % 256]) * {SIZE})
    print("sent", flush=True)
""")


def burst_into(sandbox, url: str) -> int:
    rx = sandbox.start(f"rx-{len(sandbox.procs)}", [sys.executable, "-c", RECEIVER, url])
    rx.wait_for("ready", 30, stream="stdout")
    sandbox.kill(rx, signal.SIGSTOP)  # (LCM reads its sockets in a thread: stop all of it)
    tx = sandbox.start(f"tx-{len(sandbox.procs)}", [sys.executable, "-c", SENDER])
    assert sandbox.wait(tx, 30) == 0, tx.stderr()
    sandbox.kill(rx, signal.SIGCONT)
    assert sandbox.wait(rx, 30) == 0, rx.stderr()
    return int(rx.stdout().split("got")[-1].split()[0])


@lcm_only("the udpm:// socket's kernel receive buffer")
def test_a_burst_waits_in_the_large_receive_buffer(sandbox):
    cap = kernel_receive_buffer_cap()
    assert cap is not None and cap >= RECEIVE_BUFFER, (
        f"net.core.rmem_max is {cap}: this test needs at least {RECEIVE_BUFFER} (sysctl -w net.core.rmem_max=...)")
    assert burst_into(sandbox, "") == COUNT
    small = burst_into(sandbox, "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=212992")
    assert small < COUNT // 2, small
