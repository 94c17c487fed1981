import pytest

from skillbus.bus import BusError, DropEveryNthBus, open_bus, resolve_url


def drain(bus):
    while bus.handle(0):
        pass


def test_memq_delivers_only_subscribed_channels():
    bus = open_bus("memq://")
    got = []
    bus.subscribe("A", lambda ch, d: got.append((ch, d)))
    bus.publish("A", b"one")
    bus.publish("B", b"two")
    bus.publish("A", b"three")
    drain(bus)
    assert got == [("A", b"one"), ("A", b"three")]


def test_bursts_are_not_dropped_by_the_default_queue():
    bus = open_bus("memq://")
    got = []
    bus.subscribe("A", lambda ch, d: got.append(d))
    for i in range(500):
        bus.publish("A", b"x")
    drain(bus)
    assert len(got) == 500


def test_unsubscribe_stops_delivery():
    bus = open_bus("memq://")
    got = []
    sid = bus.subscribe("A", lambda ch, d: got.append(d))
    bus.unsubscribe(sid)
    bus.publish("A", b"x")
    bus.handle(0.01)
    assert got == []


def test_a_failing_handler_does_not_stop_dispatch(caplog):
    bus = open_bus("memq://")
    got = []

    def bad(ch, d):
        raise ValueError("boom")

    bus.subscribe("A", bad)
    bus.subscribe("A", lambda ch, d: got.append(d))
    bus.publish("A", b"x")
    drain(bus)
    assert got == [b"x"]
    assert "handler for A failed" in caplog.text


@pytest.mark.parametrize("url,needle", [("carrier-pigeon://coop", "unknown scheme"),
                                        ("dds://999", "out of range"), ("dds://1?colour=red", "unknown option")])
def test_bad_urls_are_clear_errors(url, needle):
    with pytest.raises(BusError, match=needle):
        open_bus(url)


def test_url_resolution(monkeypatch):
    monkeypatch.setenv("SKILLBUS_BUS_URL", "memq://")
    assert resolve_url() == "memq://"
    assert resolve_url("udpm://239.255.76.67:7700?ttl=0").endswith("7700?ttl=0")
    monkeypatch.delenv("SKILLBUS_BUS_URL")
    assert resolve_url() == "udpm://239.255.76.67:7667?ttl=0"


def test_drop_every_nth_counts_per_channel():
    bus = DropEveryNthBus(open_bus("memq://"), 3)
    got = []
    bus.subscribe("A", lambda ch, d: got.append(d))
    bus.subscribe("B", lambda ch, d: got.append(d))
    for i in range(6):
        bus.publish("A", b"a")
        bus.publish("B", b"b")
    drain(bus)
    assert len(got) == 8 and bus.dropped == 4


def test_many_to_one_channels_use_lane_1_on_port_plus_one():
    from skillbus.bus import lane1_url, lane_of
    assert lane_of("SB_LOCKSTEP_ACK") == 1 and lane_of("ROBOT2/SB_LOCKSTEP_JOIN") == 1
    assert lane_of("SB_LOCKSTEP_CLOCK") == 0 and lane_of("SB_WM_REQ") == 0
    assert lane1_url("udpm://239.255.76.67:7667?ttl=0") == "udpm://239.255.76.67:7668?ttl=0"
    assert lane1_url("udpm://239.1.2.3") == "udpm://239.1.2.3:7668"
    assert lane1_url("memq://") == ""


def test_memq_has_one_lane_so_acks_still_arrive():
    bus = open_bus("memq://")
    got = []
    bus.subscribe("SB_LOCKSTEP_ACK", lambda ch, d: got.append(d))
    bus.publish("SB_LOCKSTEP_ACK", b"a")
    drain(bus)
    assert got == [b"a"]


def test_a_send_the_network_refuses_is_a_lost_message_not_a_crash(caplog):
    # A cable pulled (ENETDOWN) made the lockstep master die of an uncaught BusError; a
    # refused send is now a lost datagram (counted, logged), which the protocols above
    # retry or report. A message that can never fit still raises, naming the channel.
    import errno as e

    from skillbus.bus import LcmBus

    class Refusing:
        def __init__(self, err):
            self.err = err

        def publish(self, channel, data):
            raise OSError(self.err, "refused")

    bus = LcmBus("memq://")
    bus._lanes[0] = Refusing(e.ENETDOWN)
    for _ in range(3):
        bus.publish("SB_X", b"x")
    assert bus.lost_sends == 3
    assert "message lost" in caplog.text
    bus._lanes[0] = Refusing(e.EMSGSIZE)
    with pytest.raises(BusError, match="SB_X"):
        bus.publish("SB_X", b"x" * 10)


def test_nothing_joins_a_multicast_group_on_a_network_card_unless_told(monkeypatch, tmp_path):
    # The guard of open_bus, also where a udpm:// socket is made without it: an LcmBus made
    # directly, and the recorder (which joined the group on eth0 from a shell on the host).
    from skillbus import bus as bus_module
    from skillbus import udpm_record
    monkeypatch.setattr(bus_module, "route_interface", lambda address, table="": "eth9")
    monkeypatch.delenv("SKILLBUS_NETWORK", raising=False)

    def no_socket(*a, **k):
        raise AssertionError("a socket joined the group before the check")
    monkeypatch.setattr(udpm_record, "UdpmReceiver", no_socket)
    monkeypatch.setattr(bus_module, "UdpmReceiver", no_socket)
    monkeypatch.setattr(bus_module.lcm, "LCM", no_socket)
    url = "udpm://239.255.76.67:7667?ttl=0"
    with pytest.raises(BusError, match="network interface eth9"):
        bus_module.LcmBus(url)
    with pytest.raises(BusError, match="network interface eth9"):
        udpm_record.UdpmRecorder(url, str(tmp_path / "x.lcmlog"))
    assert not (tmp_path / "x.lcmlog").exists()


def test_lcm_tools_are_not_started_on_a_bus_a_network_card_would_carry(monkeypatch, tmp_path, capsys):
    # skillbus spy and skillbus replay start LCM's own tools, which have no guard: skillbus
    # checks for them, as open_bus does, and names why.
    import argparse
    from skillbus import bus as bus_module, monitor
    monkeypatch.setattr(bus_module, "route_interface", lambda address, table="": "eth9")
    monkeypatch.delenv("SKILLBUS_NETWORK", raising=False)
    monkeypatch.setattr(monitor, "run_foreground", lambda *a, **k: pytest.fail(f"started {a[0][0]}"))
    (log := tmp_path / "run.lcmlog").write_bytes(b"")
    url = "udpm://239.255.76.67:7667?ttl=0"
    assert monitor.main_spy(argparse.Namespace(url=url)) == 2
    assert monitor.main_replay(argparse.Namespace(url=url, log=str(log), speed=1.0, channels=None)) == 2
    err = capsys.readouterr().err
    assert err.count("would be joined on the network interface eth9") == 2, err


@pytest.mark.parametrize("port", ["0", "65535", "70000"])
def test_a_port_that_leaves_no_room_for_the_second_lane_is_refused_at_once(port):
    # Before, 65535 opened, then the first lockstep ack failed (LCM refused port 65536
    # for lane 1) and a C++ receiver would have bound a wrapped port.
    from skillbus.bus import LcmBus
    with pytest.raises(BusError, match=rf"port {port} \(1 to 65534: the second lane, for acks and joins, is port\+1\)"):
        LcmBus(f"udpm://239.255.76.67:{port}?ttl=0")
