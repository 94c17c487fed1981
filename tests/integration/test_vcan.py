"""The virtual SocketCAN bus: a hub process and python-can clients (interface skillbus_vcan)."""

import socket
import sys
import time

import can
import pytest

from conftest import last_json, python_tool
from skillbus.waiting import poll_until, wait_until


@pytest.fixture
def hub(sandbox, tmp_path):
    path = tmp_path / "can0.sock"
    proc = sandbox.start("can-hub", [sys.executable, "-m", "skillbus.cli", "can-hub", "--channel", path])
    wait_until(lambda: path.exists() or proc.returncode is not None, 10, f"the CAN hub's socket {path}", interval=0.02)
    assert proc.returncode is None, proc.stderr()
    return str(path), proc


def open_bus(channel, **kw):
    return can.Bus(interface="skillbus_vcan", channel=channel, **kw)


def test_two_clients_exchange_10000_frames_in_order_none_lost(sandbox, hub):
    channel, _ = hub
    a = sandbox.start("a", python_tool("can_peer.py", channel, "101", "202", "10000"))
    b = sandbox.start("b", python_tool("can_peer.py", channel, "202", "101", "10000"))
    for p in (a, b):
        assert sandbox.wait(p, 120) == 0, p.stderr()[-2000:]
        r = last_json(p.stdout())
        assert r == {"received": 10000, "in_order": True, "own": 0}, r


def received(bus, count: int, timeout: float = 10.0) -> list[int]:
    """The ids of the next `count` frames (the hub is a process: on a loaded machine it
    forwards late), then of any more that come within 0.3 s (there should be none)."""
    ids: list[int] = []

    def receive(seconds: float) -> None:
        if (m := bus.recv(timeout=seconds)) is not None:
            ids.append(m.arbitration_id)

    poll_until(lambda: len(ids) >= count, timeout, step=receive)
    while (m := bus.recv(timeout=0.3)) is not None:
        ids.append(m.arbitration_id)
    return ids


def test_own_frames_only_when_asked(hub):
    channel, _ = hub
    quiet, loud, other = open_bus(channel), open_bus(channel, receive_own_messages=True), open_bus(channel)
    try:
        quiet.send(can.Message(arbitration_id=0x10, data=b"q", is_extended_id=False))
        loud.send(can.Message(arbitration_id=0x20, data=b"l", is_extended_id=False))
        seen_by = {name: received(bus, n) for name, bus, n in (("quiet", quiet, 1), ("loud", loud, 2),
                                                                ("other", other, 2))}
        assert seen_by == {"quiet": [0x20], "loud": [0x10, 0x20], "other": [0x10, 0x20]}
    finally:
        for b in (quiet, loud, other):
            b.shutdown()


def test_filters_extended_ids_remote_and_fd_frames(hub):
    channel, _ = hub
    tx = open_bus(channel)
    rx = open_bus(channel, can_filters=[{"can_id": 0x180, "can_mask": 0x780, "extended": False}])
    fd_rx = open_bus(channel)
    try:
        for cid in (0x181, 0x201, 0x18F, 0x700):
            tx.send(can.Message(arbitration_id=cid, data=b"\x01", is_extended_id=False))
        assert received(rx, 2) == [0x181, 0x18F]
        assert received(fd_rx, 4) == [0x181, 0x201, 0x18F, 0x700]  # (unfiltered)
        tx.send(can.Message(arbitration_id=0x1ABCDEF0, data=bytes(range(64)), is_extended_id=True, is_fd=True,
                            bitrate_switch=True))
        tx.send(can.Message(arbitration_id=0x42, is_remote_frame=True, dlc=4, is_extended_id=False))
        fd = fd_rx.recv(10.0)
        assert fd.is_fd and fd.bitrate_switch and fd.is_extended_id and fd.arbitration_id == 0x1ABCDEF0
        assert bytes(fd.data) == bytes(range(64))
        rtr = fd_rx.recv(10.0)
        assert rtr.is_remote_frame and rtr.dlc == 4 and rtr.arbitration_id == 0x42
    finally:
        for b in (tx, rx, fd_rx):
            b.shutdown()


def test_a_client_that_dies_does_not_stop_the_others_and_bad_records_are_counted(sandbox, hub):
    channel, hub_proc = hub
    doomed = sandbox.start("doomed", python_tool("can_peer.py", channel, "303", "404", "100000"))
    time.sleep(0.5)
    sandbox.kill(doomed)  # mid-stream
    raw = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    raw.connect(channel)
    raw.send(b"ECHO0")
    raw.send(b"not a frame")  # 11 bytes
    a = sandbox.start("a", python_tool("can_peer.py", channel, "101", "202", "2000"))
    b = sandbox.start("b", python_tool("can_peer.py", channel, "202", "101", "2000"))
    for p in (a, b):
        assert sandbox.wait(p, 60) == 0, p.stderr()[-2000:]
        assert last_json(p.stdout())["received"] == 2000
    raw.close()
    sandbox.kill(hub_proc, 15)
    sandbox.wait(hub_proc, 10)
    assert last_json(hub_proc.stdout())["bad"] == 1


def test_no_hub_is_a_clear_error(tmp_path):
    with pytest.raises(can.CanInitializationError, match="no virtual SocketCAN hub at .*start one: skillbus can-hub"):
        open_bus(str(tmp_path / "nothing.sock"), connect_timeout=0.2)


def test_a_client_that_stops_reading_is_disconnected_not_the_bus_stopped(sandbox, tmp_path):
    path = tmp_path / "small.sock"
    hub_proc = sandbox.start("can-hub", [sys.executable, "-m", "skillbus.cli", "can-hub", "--channel", path,
                                         "--queue-limit", "500", "--stall-timeout", "5.0"])
    wait_until(path.exists, 10, f"the CAN hub's socket {path}", interval=0.02,
               diagnostic=lambda: hub_proc.stderr()[-2000:])
    sleeper = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)  # connects, never reads
    sleeper.connect(str(path))
    sleeper.send(b"ECHO0")
    a = sandbox.start("a", python_tool("can_peer.py", str(path), "101", "202", "5000"))
    b = sandbox.start("b", python_tool("can_peer.py", str(path), "202", "101", "5000"))
    for p in (a, b):
        assert sandbox.wait(p, 60) == 0, p.stderr()[-2000:]
        assert last_json(p.stdout()) == {"received": 5000, "in_order": True, "own": 0}
    sleeper.close()
    sandbox.kill(hub_proc, 15)
    sandbox.wait(hub_proc, 10)
    assert last_json(hub_proc.stdout())["stalled"] == 1
    assert "stopped reading: disconnected" in hub_proc.stderr()
