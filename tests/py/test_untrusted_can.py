"""Untrusted input on the gripper's side (docs/transport.md, "Untrusted input"): forged
physics states, set-points, SDO writes and CAN frames with values that are not finite or
out of range are counted and not acted on, and the device and the driver go on. One
process, python-can's in-process virtual bus (the real processes:
tests/integration/test_untrusted_gripper.py)."""

from __future__ import annotations

import contextlib
import math
import socket
import struct
import types
import uuid

import canopen
import pytest

from skillbus.can import cia402 as c
from skillbus.can.device import EDS, GripperDevice, summary, take_sim_state
from skillbus.can.driver import GripperDriver
from skillbus.can.fingers import FingerModel, SimFingers
from skillbus.can.hub import Client, Hub
from skillbus.can.lockstep_link import LockstepCanLink
from skillbus.can.records import check_record
from skillbus.lockstep import Stamp, StampedMessage
from skillbus.msgs import can_sync_t, sim_contact_t, sim_state_t
from skillbus.waiting import poll_until

STATE = "SB_SIM_STATE"


def networks(n: int) -> list[canopen.Network]:
    """`n` canopen networks on one fresh in-process virtual CAN bus."""
    channel = f"untrusted-{uuid.uuid4().hex[:8]}"
    out = []
    for _ in range(n):
        net = canopen.Network()
        net.NOTIFIER_CYCLE = 0.05  # (its receive thread ends this soon at disconnect)
        net.connect(interface="virtual", channel=channel)
        out.append(net)
    return out


@pytest.fixture
def rig():
    """A device with the physics fingers, and a second node (`peer`) on its bus."""
    dev_net, peer = networks(2)
    fingers = SimFingers(lambda m: None)
    dev = GripperDevice(dev_net, 5, EDS, fingers=fingers)
    yield dev, fingers, peer
    dev_net.disconnect()
    peer.disconnect()


def state(width=0.04, force=1.5, target=0.04, touching=()) -> sim_state_t:
    s = sim_state_t()
    s.finger_width, s.finger_force, s.finger_width_target = width, force, target
    for name in touching:
        contact = sim_contact_t()
        contact.body_a, contact.body_b = "finger_left", name
        s.contacts.append(contact)
    s.num_contacts = len(s.contacts)
    return s


FORGED = [("finger_width", v) for v in (math.inf, -math.inf, math.nan, 1e300, -0.5, 0.5)] + \
         [("finger_force", v) for v in (math.nan, math.inf, -1e9, 1e9)] + \
         [("finger_width_target", v) for v in (math.nan, -math.inf, 2.0)]


@pytest.mark.parametrize("field,value", FORGED)
def test_a_forged_physics_state_is_counted_and_the_fingers_keep_the_last_good_one(rig, field, value):
    dev, fingers, _ = rig
    assert take_sim_state(dev, fingers, state(touching=["green"]), STATE)
    forged = decoded(state(**{"width": 0.04, "force": 1.5, "target": 0.04} | {FIELD_ARG[field]: value}))
    assert not take_sim_state(dev, fingers, forged, STATE)
    assert (fingers.width, fingers.force, fingers.touching) == (pytest.approx(40_000), 1.5, {"green"})
    dev.step(0.01)  # what used to raise OverflowError (inf), ValueError (NaN, 1e300)
    assert dev.rejects.summary() == {f"{STATE}: {field}": 1}
    assert summary(dev, 2)["bad_input"] == 3  # the runner's own count (undecodable states) plus the rejects


FIELD_ARG = {"finger_width": "width", "finger_force": "force", "finger_width_target": "target"}


def decoded(s: sim_state_t) -> sim_state_t:
    """`s` through the wire, as a receiver gets it (LCM carries NaN and infinities as they are)."""
    return sim_state_t.decode(s.encode())


def test_a_width_a_little_outside_the_travel_is_still_a_measurement(rig):
    dev, fingers, _ = rig
    for width in (-0.0001, 0.0805):  # pads pressed together, a joint at its limit
        assert take_sim_state(dev, fingers, state(width=width), STATE)
        dev.step(0.01)
    assert dev.rejects.total == 0


def test_a_set_point_beyond_the_travel_is_not_moved_to():
    net, = networks(1)
    try:
        dev = GripperDevice(net, 5, EDS, fingers=FingerModel())
        dev.state = c.OPERATION_ENABLED
        for target in (90_000, -1, 2 ** 31 - 1):
            dev._controlword(c.CW_ENABLE_OPERATION, 0)
            dev._controlword(c.CW_ENABLE_OPERATION | c.CW_NEW_SET_POINT, target)
            assert not dev.model.moving and dev.model.target == 80_000, target  # (it used to clamp and move)
        assert dev.rejects.summary() == {"RPDO1: target position": 3}
        dev._controlword(c.CW_ENABLE_OPERATION, 0)
        dev._controlword(c.CW_ENABLE_OPERATION | c.CW_NEW_SET_POINT, 30_000)
        assert dev.model.moving and dev.model.target == 30_000
        # Outside a new set-point the target is not used, so not checked: the enable
        # sequence carries the last position seen, which may be a little below 0.
        dev._controlword(c.CW_SHUTDOWN, -3)
        assert dev.rejects.total == 3
    finally:
        net.disconnect()


@pytest.mark.parametrize("index,value", [pytest.param(i, v, id=f"0x{i:04X}={v}") for i, v in
                                         [(0x6081, 0), (0x6081, 200_001), (0x6081, 0xFFFFFFFF), (0x6060, 3),
                                          (0x6060, -1), (0x6073, 0)]])
def test_sdo_writes_out_of_range_are_aborted_and_counted(rig, index, value):
    dev, _, peer = rig
    node = canopen.RemoteNode(5, str(EDS))
    peer.add_node(node)
    before = dev.node.sdo[index].raw
    with pytest.raises(canopen.SdoAbortedError) as e:
        node.sdo[index].raw = value
    assert e.value.code == 0x06090030  # value range of parameter exceeded
    assert dev.node.sdo[index].raw == before
    assert dev.rejects.total == 1 and list(dev.rejects.by_kind) == [f"SDO 0x{index:04X}: {NAMES[index]}"]
    node.sdo[0x6081].raw = 200_000  # in range: taken
    assert dev.node.sdo[0x6081].raw == 200_000


NAMES = {0x6081: "profile velocity", 0x6060: "modes of operation", 0x6073: "force limit"}


def test_short_nmt_and_sdo_frames_are_counted_by_the_device(rig):
    dev, _, peer = rig
    peer.send_message(0x000, b"\x01")      # NMT: command and node id expected
    peer.send_message(0x605, b"")          # SDO request: 8 bytes expected
    peer.send_message(0x605, b"\x40\x00")
    poll_until(lambda: dev.rejects.total == 3, 5, interval=0.01)
    assert dev.rejects.summary() == {"COB-ID 0x000: length": 1, "COB-ID 0x605: length": 2}
    node = canopen.RemoteNode(5, str(EDS))
    peer.add_node(node)
    assert node.sdo[0x6081].raw == 50_000  # and it still answers


# -- the driver ---------------------------------------------------------------------------------------

@pytest.fixture
def driver():
    drv_net, peer = networks(2)
    d = GripperDriver(drv_net, 5)
    yield d, peer
    drv_net.disconnect()
    peer.disconnect()


def tpdo(statusword=0x0637, position=40_000, grip=c.GRIP_REACHED) -> bytes:
    return struct.pack("<HiB", statusword, position, grip)


def test_a_tpdo_with_a_position_or_grip_state_no_gripper_reports_is_counted_not_shown(driver):
    d, peer = driver
    peer.send_message(0x185, tpdo())
    poll_until(lambda: d.status().updates == 1, 5, interval=0.01)
    for forged in (tpdo(position=10 ** 6), tpdo(position=-2 ** 31), tpdo(position=-6_000), tpdo(grip=0xF2)):
        peer.send_message(0x185, forged)
    peer.send_message(0x185, tpdo(position=-3))  # a width a hair below closed: a measurement
    poll_until(lambda: d.status().updates == 2, 5, interval=0.01)
    s = d.status()
    assert (s.position_um, s.grip) == (-3, c.GRIP_REACHED)
    assert d.malformed == 4
    assert d.rejects.summary() == {"TPDO1: grip state": 1, "TPDO1: position actual value": 3}


def test_short_heartbeats_emcys_and_sdo_answers_and_unknown_nmt_states_are_counted(driver):
    d, peer = driver
    peer.send_message(0x705, b"")                   # no state
    peer.send_message(0x705, b"\x42")               # a state no node sends
    peer.send_message(0x085, b"\x10\x23\x01")       # EMCY: 8 bytes expected
    peer.send_message(0x585, b"\x60")               # SDO answer: 8 bytes expected
    poll_until(lambda: d.malformed == 4, 5, interval=0.01)
    assert d.rejects.summary() == {"COB-ID 0x085: length": 1, "COB-ID 0x585: length": 1,
                                   "COB-ID 0x705: NMT state": 1, "COB-ID 0x705: length": 1}
    assert d._last_heartbeat is None and not d.status().faults  # none of them was taken as a heartbeat or a fault
    peer.send_message(0x705, b"\x7f")               # a real one still counts
    peer.send_message(0x085, struct.pack("<HB5s", 0x2310, 1, bytes(5)))
    poll_until(lambda: d._last_heartbeat is not None and d.status().faults, 5, interval=0.01)
    assert d.status().faults == ["EMCY 0x2310: over-current (blocked too long)"]
    assert d.malformed == 4


# -- the lockstep CAN link --------------------------------------------------------------------------

class QuietBus:
    hub_losses, fault, path = 0, None, "/run/skillbus/gripper0.sock"

    def recv(self, timeout):
        return None

    def shutdown(self) -> None:
        pass


def sync(frames: int, can_channel: str = "gripper0.sock") -> StampedMessage:
    m = can_sync_t()
    m.can_channel, m.frames = can_channel, frames
    return StampedMessage("SB_CAN_SYNC", Stamp(4, 0, "gripper", 0), m.encode())


def test_can_sync_announcements_that_do_not_decode_or_count_nonsense_are_counted():
    heard = []

    def notify(can_id, data, timestamp):
        heard.append(can_id)
        struct.unpack_from("B", data)  # as canopen's heartbeat handler does

    participant = types.SimpleNamespace(subscribe=lambda *a, **k: None)
    network = types.SimpleNamespace(bus=None, notify=notify)
    link = LockstepCanLink(participant, QuietBus(), "gripper0.sock", network, set(), timeout=0.2)
    try:
        link._on_sync(StampedMessage("SB_CAN_SYNC", Stamp(4, 0, "gripper", 0), b"\x00" * 20))  # used to raise
        for frames in (-1, 2 ** 31 - 1):
            link._on_sync(sync(frames))
        link._on_sync(sync(1))
        assert link._expected == [("gripper", 1)]  # only the sane one: the next frame waits for nothing else
        import can
        link._queue.append(can.Message(arbitration_id=0x705, data=b"", is_extended_id=False))
        link.begin_frame(5)  # a frame canopen cannot unpack: counted, the frame goes on
        assert heard == [0x705]
        assert link.rejects.summary() == {"CAN 0x705: frame": 1, "SB_CAN_SYNC: frames": 2,
                                          "SB_CAN_SYNC: not a can_sync_t": 1}
    finally:
        link.shutdown()


# -- the virtual SocketCAN hub ---------------------------------------------------------------------

def test_the_hub_drops_records_whose_length_byte_overflows_the_data(tmp_path):
    good = struct.pack("=IB3x8s", 0x205, 6, bytes(8))
    classic_9 = struct.pack("=IB3x8s", 0x205, 9, bytes(8))
    fd_65 = struct.pack("=IBB2x64s", 0x205, 65, 0, bytes(64))
    for bad in (classic_9, fd_65):
        with pytest.raises(ValueError, match="data bytes"):
            check_record(bad)
    with hub_with_two_clients(tmp_path) as (hub, sender, receiver, sender_end, receiver_end):
        for rec in (classic_9, fd_65, good):
            sender_end.send(rec)
        hub._read(sender)
        assert hub.bad == 2 and hub.relayed == 1 and relayed_to(receiver, receiver_end) == [good]


@contextlib.contextmanager
def hub_with_two_clients(tmp_path):
    """A hub (not running: the test calls its handlers) with two clients on socket pairs:
    (hub, sender, receiver, the sender's own end of its socket, the receiver's)."""
    hub = Hub(tmp_path / "hub.sock")
    pairs = [socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET) for _ in range(2)]
    try:
        sender, receiver = Client(pairs[0][0]), Client(pairs[1][0])
        for cl in (sender, receiver):
            cl.sock.setblocking(False)
            hub.clients[cl.sock.fileno()] = cl
            hub.sel.register(cl.sock, 1, cl)
        yield hub, sender, receiver, pairs[0][1], pairs[1][1]
    finally:
        hub.close()
        for _, far in pairs:
            far.close()


def relayed_to(client, far_end) -> list[bytes]:
    """What the hub relayed to `client`: sent at once (read at its far end) or still queued."""
    far_end.setblocking(False)
    got = []
    while True:
        try:
            got.append(far_end.recv(100))
        except BlockingIOError:
            return got + list(client.out)


def test_records_sent_just_before_a_client_closes_are_relayed(tmp_path):
    """A client that sends and closes at once, with records of ours unread (a rogue node in
    test_gripper_can): its socket reports ECONNRESET once, before what it sent. The hub
    relays those records, then drops it."""
    rec = struct.pack("=IB3x8s", 0x185, 3, bytes(8))
    with hub_with_two_clients(tmp_path) as (hub, sender, receiver, sender_end, receiver_end):
        sender.sock.send(b"unread by the sender")  # (as the hub's JOINED, or a frame relayed to it)
        sender_end.send(rec)
        sender_end.send(rec)
        sender_end.close()
        hub._read(sender)
        assert hub.relayed == 2 and relayed_to(receiver, receiver_end) == [rec, rec]
        assert sender.sock.fileno() == -1 and len(hub.clients) == 1  # and then it was dropped
