"""Channel names with several robots: the same as the C++ side (tests/cpp/test_channels.cpp),
and robot names that cannot be part of a channel are refused."""

import pytest

from skillbus import channels
from skillbus.channels import channel, current_robot, robot_channel, robot_scoped, set_robot, valid_robot_name

OWN = ["SB_ROBOT_ARM_STATE", "SB_ROBOT_ARM_CMD", "SB_ROBOT_OBJECTS", "SB_ROBOT_CMD_REPLY", "SB_SKILL_REQ",
       "SB_SKILL_PROGRESS", "SB_SKILL_MANAGER", "SB_SKILL_HEARTBEAT", "SB_SKPROC_SKILLS_REQ", "SB_MOTION_REP",
       "SB_CAN_SYNC", "SB_SIM_STATE", "SB_SIM_GRIPPER_CMD", "SB_SIM_CMD_REPLY", "SB_SIM_ATTACH", "SB_ROBOT_ARTICULATION"]
SHARED = ["SB_WM_REQ", "SB_WM_CHANGES", "SB_WM_TXN", "SB_LOCKSTEP_CLOCK", "SB_LOCKSTEP_ACK", "SB_LOCKSTEP_END",
          "SB_SIM_REQ", "SB_SIM_REP", "SB_MANAGERS", "SB_MANAGERS_PROBE", "SB_LOG_MARK"]


@pytest.fixture(autouse=True)
def no_robot(monkeypatch):
    monkeypatch.delenv("SKILLBUS_ROBOT", raising=False)
    monkeypatch.delenv("SKILLBUS_NAMESPACE", raising=False)
    monkeypatch.setattr(channels, "_robot", None)


@pytest.mark.parametrize("name", OWN)
def test_a_robots_own_channels_go_under_its_name(name):
    assert robot_scoped(name)
    assert robot_channel(name, "r2") == f"r2/{name}" and robot_channel(name, "") == name


@pytest.mark.parametrize("name", SHARED)
def test_shared_channels_have_no_robot(name):
    assert not robot_scoped(name) and robot_channel(name, "r2") == name


def test_the_process_robot_comes_from_set_robot_else_the_environment(monkeypatch):
    monkeypatch.setenv("SKILLBUS_ROBOT", "envbot")
    assert current_robot() == "envbot" and channel("SB_ROBOT_ARM_CMD") == "envbot/SB_ROBOT_ARM_CMD"
    set_robot("r1")
    assert channel("SB_SKILL_REQ") == "r1/SB_SKILL_REQ" and channel("SB_WM_REQ") == "SB_WM_REQ"
    monkeypatch.setenv("SKILLBUS_NAMESPACE", "lab_")
    assert channel("SB_SKILL_REQ") == "lab_r1/SB_SKILL_REQ" and channel("SB_WM_REQ") == "lab_SB_WM_REQ"
    set_robot("")  # explicitly none, whatever the environment says
    assert channel("SB_SKILL_REQ") == "lab_SB_SKILL_REQ"


@pytest.mark.parametrize("bad", ["1r", "r/2", "r 2", "r-2", "_r", "r.2", "ü", "r" * 25])
def test_names_that_cannot_name_a_channel_are_refused(bad):
    assert not valid_robot_name(bad)
    with pytest.raises(ValueError, match="a letter, then letters, digits or _"):
        set_robot(bad)
    assert current_robot() == ""


def test_rpc_areas_follow_the_robot():
    from skillbus.rpc import reply_channel, request_channel
    set_robot("r2")
    assert request_channel("SKILL") == "r2/SB_SKILL_REQ" and reply_channel("SKPROC_SKILLS") == "r2/SB_SKPROC_SKILLS_REP"
    assert request_channel("WM") == "SB_WM_REQ" and request_channel("SIM") == "SB_SIM_REQ"


def test_a_channel_name_longer_than_lcm_allows_is_refused_naming_its_parts(monkeypatch):
    # LCM ends channel names at 63 bytes: a longer one registers, subscribes and then
    # never carries a message, so it must fail where it is made, saying which part is long.
    from skillbus.rpc import request_channel
    name = "P" * 49  # SB_SKPROC_ + 49 + _REQ = 63 bytes: the longest that fits
    assert len(request_channel("SKPROC_" + name)) == 63
    with pytest.raises(ValueError, match=r"64 bytes.*LCM.*63"):
        request_channel("SKPROC_" + name + "Q")
    set_robot("r2")  # the robot's name and its / count
    with pytest.raises(ValueError, match=r"'r2/SB_SKPROC_P+_REQ' is 66 bytes.*robot r2"):
        request_channel("SKPROC_" + name)
    assert robot_channel("SB_WM_REQ", "r2") == "SB_WM_REQ"  # (shared: not under the robot)
    set_robot("")
    monkeypatch.setenv("SKILLBUS_NAMESPACE", "N" * 60)
    with pytest.raises(ValueError, match=r"SKILLBUS_NAMESPACE"):
        channel("SB_WM_REQ")


def test_the_limit_is_in_bytes_as_lcm_counts_them():
    from skillbus.bus import BusError, open_bus
    bus = open_bus("memq://")
    bus.subscribe("é" * 31 + "x", lambda ch, data: None)  # 63 bytes: fits (LCM takes any bytes)
    with pytest.raises(BusError, match="64 bytes"):
        bus.subscribe("é" * 32, lambda ch, data: None)  # 32 characters, 64 bytes


@pytest.mark.parametrize("part,bad", [("name", "SB_SKPROC_MY-ARM_REQ"), ("name", "SB_X.Y"), ("name", "SB_é"),
                                      ("name", "9SB_X"), ("namespace", "lab-"), ("namespace", "lab ")])
def test_a_channel_name_a_dds_topic_refuses_is_refused_on_either_transport(monkeypatch, part, bad):
    # Cyclone DDS 0.10 (the C++ side) takes letters, digits, _ and / in a topic name, not
    # a leading digit; before, such names ran on LCM and failed on DDS at their first use.
    if part == "namespace":
        monkeypatch.setenv("SKILLBUS_NAMESPACE", bad)
        with pytest.raises(ValueError, match=rf"cannot be in a channel name .*\$SKILLBUS_NAMESPACE is '{bad}'"):
            channel("SB_WM_REQ")
    else:
        with pytest.raises(ValueError, match="cannot (be in|start with a digit)"):
            channel(bad)
    monkeypatch.setenv("SKILLBUS_NAMESPACE", "lab_")
    assert channel("SB_WM_REQ") == "lab_SB_WM_REQ" and robot_channel("SB_SKILL_REQ", "r2") == "lab_r2/SB_SKILL_REQ"


def test_every_bus_refuses_to_subscribe_to_a_channel_lcm_cannot_carry():
    from skillbus.bus import BusError, open_bus
    bus = open_bus("memq://")
    with pytest.raises(BusError, match="64 bytes"):
        bus.subscribe("C" * 64, lambda ch, data: None)
    with pytest.raises(BusError, match="64 bytes"):
        bus.publish("C" * 64, b"x")


def test_every_bus_refuses_a_message_larger_than_a_receiver_reassembles():
    # Before, it was sent, and every receiver dropped it (LCM reassembles at most 16 MiB):
    # an RPC request that large timed out without a word on why.
    from skillbus.bus import MAX_MESSAGE_BYTES, BusError, open_bus
    from skillbus.udpm import MAX_PARTIAL_BYTES
    assert MAX_MESSAGE_BYTES == MAX_PARTIAL_BYTES == 16 << 20
    bus = open_bus("memq://")
    got: list[int] = []
    bus.subscribe("SB_BIG", lambda ch, data: got.append(len(data)))
    # (the size on the wire: with a key, the signature's trailer counts too)
    with pytest.raises(BusError, match=rf"a message of \d+ bytes on SB_BIG: over the {MAX_MESSAGE_BYTES} bytes"):
        bus.publish("SB_BIG", bytes(MAX_MESSAGE_BYTES + 1))
    bus.publish("SB_BIG", bytes(MAX_MESSAGE_BYTES - 1024))
    bus.handle(1.0)
    assert got == [MAX_MESSAGE_BYTES - 1024]
