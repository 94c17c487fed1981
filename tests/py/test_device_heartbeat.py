"""The gripper device's heartbeat under lockstep: sent from the frames, by sim time, at
the period 0x1017 holds. The device keeps that period as it is written (it is read at
every frame), so what a driver writes by SDO, and only what the device took, counts.
The frames a device at rest and a driver leave to the quiet-frame core (their quiet
horizons) end before anything they would send or judge: the event timer's TPDO, the
heartbeat, the heartbeat's loss."""

from __future__ import annotations

import canopen
import pytest

from skillbus.can.device import EDS, GripperDevice
from skillbus.can.fingers import SimFingers

from test_untrusted_can import networks

MS = 1_000_000


def heartbeats(dev: GripperDevice, monkeypatch, times_ms: list[int]) -> list[int]:
    """The sim times (ms) among `times_ms` at which the device sent its heartbeat."""
    sent: list[int] = []
    now = [0]
    real = dev.network.send_message

    def send(can_id, data, remote=False):
        if can_id == 0x705:
            sent.append(now[0])
        else:
            real(can_id, data, remote)

    monkeypatch.setattr(dev.network, "send_message", send)
    for t in times_ms:
        now[0] = t
        dev.heartbeat_if_due(t * MS)
    monkeypatch.setattr(dev.network, "send_message", real)
    return sent


def test_the_period_written_by_sdo_is_the_one_the_frames_keep(device_and_driver, monkeypatch):
    dev, node = device_and_driver
    node.sdo[0x1017].raw = 100
    assert heartbeats(dev, monkeypatch, list(range(0, 260, 20))) == [0, 100, 200]
    node.sdo[0x1017].raw = 40
    assert heartbeats(dev, monkeypatch, list(range(260, 400, 20))) == [300, 340, 380]
    node.sdo[0x1017].raw = 0  # the heartbeat off
    assert heartbeats(dev, monkeypatch, list(range(400, 600, 20))) == []


def test_a_write_the_device_refuses_leaves_the_period(device_and_driver, monkeypatch):
    dev, node = device_and_driver
    node.sdo[0x1017].raw = 100

    def refuse(index, subindex, od, data):
        if index == 0x1017:
            raise canopen.SdoAbortedError(0x08000020)  # (a callback before the device's own refuses)

    dev.node._write_callbacks.insert(0, refuse)
    with pytest.raises(canopen.SdoAbortedError):
        node.sdo[0x1017].raw = 20
    assert dev.node.sdo[0x1017].raw == 100
    assert heartbeats(dev, monkeypatch, list(range(0, 220, 20))) == [0, 100, 200]


def operational_device():
    dev_net, peer = networks(2)
    dev = GripperDevice(dev_net, 5, EDS, fingers=SimFingers(lambda m: None))
    dev.event_every = 10
    dev.boot()
    dev.node.nmt.state = "OPERATIONAL"
    return dev, (dev_net, peer)


def run_frames(dev: GripperDevice, monkeypatch, frames: int, use_horizon: bool) -> tuple[list, list[int]]:
    """(frame, COB-ID) of what the device sends at rest over `frames` frames of 20 ms: at
    every frame, or only at those past its quiet horizon (as the quiet-frame core leaves
    them to Python), catching up on the frames between. Also the frames Python ran."""
    sent: list = []
    frame = [0]
    real = dev.network.send_message
    monkeypatch.setattr(dev.node.tpdo[1], "transmit", lambda: sent.append((frame[0], "TPDO1")))
    monkeypatch.setattr(dev.network, "send_message",
                        lambda can_id, data, remote=False: sent.append((frame[0], hex(can_id))))
    ran, last, horizon = [], None, None
    for f in range(frames):
        t = f * 20 * MS
        if use_horizon and horizon is not None and f <= horizon[0] and t < horizon[1]:
            continue  # acked by the core
        if last is not None and f - last > 1:
            dev.frames_passed(f - last - 1)
        frame[0] = f
        dev.step(0.02)
        dev.heartbeat_if_due(t)
        ran.append(f)
        last = f
        horizon = dev.quiet_horizon(f)
    monkeypatch.setattr(dev.network, "send_message", real)
    return sent, ran


def test_at_rest_frames_past_the_horizon_send_what_every_frame_sends(monkeypatch):
    every, python = operational_device(), operational_device()
    try:
        a, ran_a = run_frames(every[0], monkeypatch, 200, use_horizon=False)
        b, ran_b = run_frames(python[0], monkeypatch, 200, use_horizon=True)
    finally:
        for _, nets in (every, python):
            for n in nets:
                n.disconnect()
    assert a == b  # the TPDO's event timer and the heartbeat (0x705), in the same frames
    assert ("0x705" in {c for _, c in a}) and ("TPDO1" in {c for _, c in a})
    assert len(ran_a) == 200 and len(ran_b) < 200 // 3  # most frames at rest were the core's


def test_no_horizon_while_the_fingers_move_or_before_the_first_heartbeat(device_and_driver):
    dev, _ = device_and_driver
    dev.node.nmt.state = "OPERATIONAL"
    dev.event_every = 10
    with dev.lock:
        dev._heartbeat_ms = 100
    assert dev.quiet_horizon(5) is None  # no heartbeat sent yet: the next frame sends it
    dev.heartbeat_if_due(0)
    assert dev.quiet_horizon(5) is not None
    dev.model.moving = True
    assert dev.quiet_horizon(5) is None


def test_the_drivers_horizon_ends_before_the_heartbeat_counts_as_lost():
    from skillbus.can.driver import GripperDriver
    drv_net, peer = networks(2)
    now = [0.0]
    try:
        d = GripperDriver(drv_net, 5, clock=lambda: now[0])
        d.begin_startup()
        d.advance()
        assert d.quiet_horizon() is None  # the start-up runs one step a frame
        d._startup = None
        d._last_heartbeat = 1.0
        through, before_ns = d.quiet_horizon()
        assert through == 2**63 - 1 and before_ns == 1_299_000_000  # 3 x 100 ms, a millisecond early
        for t_ns in (before_ns - 20 * MS, before_ns - 1, before_ns):  # the frames it may cover: no loss yet
            now[0] = t_ns * 1e-9
            d.poll()
            assert d._hb_fault is None
        now[0] = 1.31
        d.poll()
        assert d._hb_fault is not None
        assert d.quiet_horizon() == (2**63 - 1, 2**63 - 1)  # lost: only a heartbeat changes that
        d._recovery_asked = True
        assert d.quiet_horizon() is None
    finally:
        drv_net.disconnect()
        peer.disconnect()
