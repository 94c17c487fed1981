"""The dds:// URL and the envelope (skillbus.dds; the C++ twin: tests/cpp/test_bus.cpp)."""

import pytest

from skillbus.bus import BusError
from skillbus.dds import DdsUrlError, check_local, config_xml, parse_url, unwrap, wrap


@pytest.mark.parametrize("bad", ["dds://", "dds://x", "dds://233", "dds://1?colour=red", "dds://1?state=sometimes"])
def test_a_wrong_url_is_an_error_naming_it(bad):
    with pytest.raises(DdsUrlError, match=bad.replace("?", r"\?")):
        parse_url(bad)


def test_another_host_needs_the_network_allowed():
    check_local(parse_url("dds://1?peers=localhost,127.0.0.2"), "u", allowed="")
    for url in ("dds://1?interface=10.0.0.1", "dds://1?peers=robot-b"):
        with pytest.raises(BusError, match="--network"):
            check_local(parse_url(url), url, allowed="")
    check_local(parse_url("dds://1?peers=robot-b"), "u", allowed="veth0")


def test_the_default_configuration_is_loopback_only():
    xml = config_xml(parse_url("dds://3"))
    assert '<NetworkInterface address="127.0.0.1" multicast="false"/>' in xml
    assert "<AllowMulticast>false</AllowMulticast>" in xml
    assert '<Peers><Peer address="localhost"/></Peers>' in xml


def test_envelopes_carry_any_bytes_and_refuse_what_is_cut():
    for data in (b"", b"a", b"abcd", bytes(range(256)) * 300):
        assert unwrap(wrap(data)) == data
    assert unwrap(wrap(b"abcdef")[:9]) is None


def test_a_cyclone_configuration_from_elsewhere_is_used_only_where_the_network_is_allowed():
    # A ROS 2 shell's $CYCLONEDDS_URI (multicast on the network card) was used as it was:
    # the robot's bus went on the network without anyone saying so.
    import pytest
    from skillbus.bus import BusError
    from skillbus.dds import OWN_CONFIG_ENV, cyclone_config
    u = parse_url("dds://3")
    env = {"CYCLONEDDS_URI": "file:///etc/ros/cyclone.xml"}
    with pytest.raises(BusError, match=r"\$CYCLONEDDS_URI is set \(file:///etc/ros/cyclone.xml\).*--network IFACE"):
        cyclone_config(u, "dds://3", env)
    env["SKILLBUS_NETWORK"] = "eth0"  # told: the user's configuration, as it is
    assert cyclone_config(u, "dds://3", env) == "file:///etc/ros/cyclone.xml"
    own: dict = {}
    xml = cyclone_config(u, "dds://3", own)  # none given: skillbus's own, recorded as its own
    assert xml == config_xml(u) and own[OWN_CONFIG_ENV] == xml
    child = {"CYCLONEDDS_URI": xml, OWN_CONFIG_ENV: xml}  # inherited from a skillbus parent: not the user's
    assert cyclone_config(parse_url("dds://3?peers=localhost"), "dds://3?peers=localhost", child) == \
        config_xml(parse_url("dds://3?peers=localhost"))
