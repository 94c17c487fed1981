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
    import os, sys, time
    from skillbus.bus import open_bus, DEFAULT_URL
    from skillbus.waiting import wait_until
    url = sys.argv[1] or DEFAULT_URL
    bus = open_bus(url)
    got = []
    bus.subscribe("SB_BURST", lambda ch, data: got.append(len(data)))
    print("ready", flush=True)
    # (stopped here until the burst has been sent; then the test says go)
    wait_until(lambda: os.path.exists(sys.argv[2]), 60, "the go file")
    while bus.handle(2.0):  # (the burst is in the socket's buffer, what of it was kept: read it all)
        pass
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
    go = sandbox.log_dir / f"go-{len(sandbox.procs)}"
    rx = sandbox.start(f"rx-{len(sandbox.procs)}", [sys.executable, "-c", RECEIVER, url, str(go)])
    rx.wait_for("ready", 30, stream="stdout")
    sandbox.kill(rx, signal.SIGSTOP)  # (LCM reads its sockets in a thread: stop all of it)
    tx = sandbox.start(f"tx-{len(sandbox.procs)}", [sys.executable, "-c", SENDER])
    assert sandbox.wait(tx, 30) == 0, tx.stderr()
    go.touch()
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
