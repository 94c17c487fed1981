"""skillbus.robot.arm_state_decode gives what LCM's generated decoder gives (through
skillbus.msgs.decode) for every byte string: valid states, states cut short or grown,
and states with bytes flipped (seeded)."""

import struct

import pytest

from damaged import cut_and_grown, flipped, same_stamp_and_fields

from skillbus.msgs import decode, robot_arm_state_t
from skillbus.robot.arm_state_decode import decode_arm_state

FIELDS = ("num_joints", "joint_names", "position", "velocity", "effort", "tool_pose", "arm_command_id",
          "arm_moving", "arm_tracking_error")


def state(n: int, names: list[str] | None = None, command: str = "cmd-7") -> bytes:
    s = robot_arm_state_t()
    s.header.frame, s.header.sim_time_ns, s.header.sender, s.header.seq = 42, 840_000_000, "sim", 3
    s.num_joints = n
    s.joint_names = names if names is not None else [f"joint_{i}" for i in range(n)]
    s.position = [0.1 * i for i in range(n)]
    s.velocity = [-0.2 * i for i in range(n)]
    s.effort = [1.5 * i for i in range(n)]
    s.tool_pose = [0.4, 0.15, 0.5, 0.0, 1.0, 0.0, 0.0]
    s.arm_command_id = command
    s.arm_moving = True
    s.arm_tracking_error = 0.003
    return s.encode()


def same(data: bytes, valid: bool = False) -> None:
    want = decode(robot_arm_state_t, data)
    got = decode_arm_state(data)
    if want is None:
        assert got is None, data
        return
    assert got is not None, data
    same_stamp_and_fields(got, want, FIELDS)
    if valid:
        assert got.encode() == data


@pytest.mark.parametrize("data", [state(6), state(0), state(1, ["ß-gelenk"], ""), state(7, command="x" * 300)])
def test_valid_states_decode_alike(data):
    same(data, valid=True)
    assert decode_arm_state(data) is not None


def test_every_cut_and_growth_is_refused_alike():
    for data in cut_and_grown(state(6)):
        same(data)


def test_flipped_bytes_and_odd_counts_decode_alike():
    for data in flipped(state(6), 20261204, 3000):
        same(data)
    # A negative joint count, a string longer than the message, invalid UTF-8 in a name.
    at = 8 + 16 + 4 + 4 + 4  # fingerprint, frame and time, "sim\0", seq
    for count in (-1, -(2 ** 31), 2 ** 31 - 1):
        same(data[:at] + struct.pack(">i", count) + data[at + 4:])
    same(data[:at + 4] + struct.pack(">I", 2 ** 32 - 1) + data[at + 8:])
    bad_utf8 = bytearray(state(1, ["abc"]))
    bad_utf8[bad_utf8.index(b"abc")] = 0xFF
    same(bytes(bad_utf8))
    assert decode_arm_state(bytes(bad_utf8)).joint_names == ["\ufffdbc"]


def test_forged_counts_do_not_grow_the_decoders_structs():
    # A struct per joint count is kept: counts that cannot fit the message never get one.
    from skillbus.robot import arm_state_decode

    data = state(6)
    at = 8 + 16 + 4 + 4 + 4
    before = len(arm_state_decode._DOUBLES)
    for count in range(1000, 1300):
        # `count` names of one byte each (their NUL), then nothing: the names fit, the
        # arrays after them cannot.
        forged = data[:at] + struct.pack(">i", count) + (struct.pack(">I", 1) + b"\0") * count
        assert decode_arm_state(forged) is None
        assert decode(robot_arm_state_t, forged) is None
    assert len(arm_state_decode._DOUBLES) <= before + 1
