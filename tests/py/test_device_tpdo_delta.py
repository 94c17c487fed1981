"""When the gripper device sends TPDO1 (its status) under lockstep: at once when its
statusword or grip state changes or its position has moved at least 0x2001 (TPDO1
position delta, µm; 50 by default) from the position last sent, else on its event timer
(every 10th frame). Holding an object the fingers move by a few micrometres a frame; those
moves wait for the timer. The frames are real python-can frames on a virtual bus: what
the device decides to send is what the driver's node receives."""

from __future__ import annotations

import time

import canopen
import pytest

from skillbus.can import cia402 as c


@pytest.fixture
def sending(device_and_driver):
    """The device operational with the lockstep event timer, and the TPDO1 positions its
    peer receives, in order."""
    dev, node = device_and_driver
    got: list[int] = []
    node.network.subscribe(0x180 + 5, lambda cob, data, ts: got.append(int.from_bytes(bytes(data[2:6]), "little")))
    dev.event_every = 10
    dev.node.nmt.state = "OPERATIONAL"
    sent = [0]
    transmit = dev.node.tpdo[1].transmit

    def counted() -> None:
        sent[0] += 1
        transmit()

    dev.node.tpdo[1].transmit = counted

    def step(width: float) -> None:
        dev.model.width = width
        dev._publish_status(event=False)

    def received() -> list[int]:
        deadline = time.monotonic() + 5.0
        while len(got) < sent[0] and time.monotonic() < deadline:
            time.sleep(0.005)
        assert len(got) == sent[0], f"{sent[0]} TPDO1 sent, {len(got)} received"
        return list(got)

    step(41_000)  # the first status always goes out
    yield dev, node, step, received


def test_moves_below_the_delta_wait_and_the_move_that_reaches_it_goes_out(sending):
    dev, _, step, received = sending
    assert dev._position_delta == 50  # the EDS's default
    for width in (41_010, 41_020, 41_040, 40_960):  # each within 50 um of the 41,000 sent
        step(width)
    assert received() == [41_000]
    step(41_050)  # 50 um from the last sent
    step(41_080)  # 30 um from that one
    step(41_000)  # 50 um back
    assert received() == [41_000, 41_050, 41_000]


def test_a_change_of_state_goes_out_at_once_with_whatever_position(sending):
    dev, _, step, received = sending
    step(41_001)
    dev.state = c.FAULT  # the statusword changes
    step(41_002)
    assert received() == [41_000, 41_002]


def test_the_event_timer_sends_the_latest_position_every_tenth_frame(sending):
    _, _, step, received = sending
    for k in range(1, 21):
        step(41_000 + k)  # a micrometre a frame: never 50 from the last sent
    assert received() == [41_000, 41_010, 41_020]


def test_a_delta_of_zero_sends_every_change(sending):
    dev, node, step, received = sending
    node.sdo[0x2001].raw = 0  # an SDO download, as a driver configures it
    assert dev._position_delta == 0
    step(41_001)
    step(41_001)  # no change: nothing
    step(41_000)
    assert received() == [41_000, 41_001, 41_000]


def test_a_delta_beyond_the_travel_is_refused_and_the_old_one_kept(sending):
    dev, node, _, _ = sending
    with pytest.raises(canopen.SdoAbortedError) as e:
        node.sdo[0x2001].raw = 80_001
    assert e.value.code == 0x06090030
    assert dev._position_delta == 50 and node.sdo[0x2001].raw == 50


def test_on_the_wall_clock_every_step_sends(sending):
    dev, _, step, received = sending
    dev.event_every = 1  # the standalone device's event timer: every step
    step(41_001)
    step(41_001)
    assert received() == [41_000, 41_001, 41_001]


def test_a_grip_state_change_alone_goes_out_at_once(sending):
    dev, _, step, received = sending
    sw_before = dev._last_sent[0]
    f = dev.model  # closing on a cube and stalled on it: gripped, its statusword as it was
    f.moving, f.target, f.force, f.touching, f.acknowledged = True, 0.0, f.force_limit_n, {"cube"}, True
    step(41_001)
    assert received() == [41_000, 41_001]
    assert dev._last_sent[0] == sw_before and dev._last_sent[2] & c.GRIP_GRIPPED


def test_an_event_send_ignores_the_delta(sending):
    dev, _, _, received = sending
    dev.model.width = 41_001
    dev._publish_status(event=True)  # (a controlword handled: answered at once)
    assert received() == [41_000, 41_001]


def test_an_eds_without_the_delta_object_sends_every_change(tmp_path):
    """A device description written before 0x2001 existed still makes a working device,
    which sends every change as the device did then."""
    import re

    from skillbus.can.device import EDS, GripperDevice
    from skillbus.can.fingers import SimFingers
    from test_untrusted_can import networks

    text = EDS.read_text()
    text = re.sub(r"\n\[2001\]\n(?:[^\[\n][^\n]*\n)*", "\n", text)
    text = text.replace("SupportedObjects=2\n1=0x2000\n2=0x2001\n", "SupportedObjects=1\n1=0x2000\n")
    assert "[2001]" not in text and "0x2001" not in text
    old = tmp_path / "old.eds"
    old.write_text(text)
    net, = networks(1)
    try:
        dev = GripperDevice(net, 5, old, fingers=SimFingers(lambda m: None))
        assert dev._position_delta == 0
        sent = []
        dev.node.tpdo[1].transmit = lambda: sent.append(dev._last_sent[1])
        dev.event_every = 10
        dev.node.nmt.state = "OPERATIONAL"
        for width in (41_000, 41_001, 41_002):
            dev.model.width = width
            dev._publish_status(event=False)
        assert sent == [41_000, 41_001, 41_002]
    finally:
        net.disconnect()
