"""The gripper device's heartbeat under lockstep: sent from the frames, by sim time, at
the period 0x1017 holds. The device keeps that period as it is written (it is read at
every frame), so what a driver writes by SDO, and only what the device took, counts."""

from __future__ import annotations

import canopen
import pytest

from skillbus.can.device import EDS, GripperDevice
from skillbus.can.fingers import SimFingers

from test_untrusted_can import networks

MS = 1_000_000


@pytest.fixture
def device_and_driver():
    dev_net, peer = networks(2)
    dev = GripperDevice(dev_net, 5, EDS, fingers=SimFingers(lambda m: None))
    node = canopen.RemoteNode(5, str(EDS))
    peer.add_node(node)
    dev.boot()
    yield dev, node
    dev_net.disconnect()
    peer.disconnect()


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
