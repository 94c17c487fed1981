"""skillbus.sim.state_decode gives what LCM's generated decoder gives (through
skillbus.msgs.decode) for every byte string: valid states, states cut short or grown,
states with bytes flipped (seeded), and the counts the generated decoder reads its own
way (negative object and contact counts)."""

import struct

import pytest

from damaged import cut_and_grown, fields, flipped, same_stamp_and_fields

from skillbus.msgs import decode, sim_contact_t, sim_object_t, sim_state_t
from skillbus.sim.state_decode import decode_sim_state

FIELDS = [f for f in sim_state_t.__slots__ if f not in ("header", "objects", "contacts")]


def state(joints: int = 8, objects: int = 3, contacts: int = 2, name: str = "joint", command: str = "cmd-3") -> bytes:
    s = sim_state_t()
    s.header.frame, s.header.sim_time_ns, s.header.sender, s.header.seq = 812, 16_240_000_000, "sim", 5
    s.num_joints = joints
    s.joint_names = [f"{name}_{i}" for i in range(joints)]
    s.position = [0.25 * i for i in range(joints)]
    s.velocity = [-0.5 * i for i in range(joints)]
    s.effort = [3.0 * i for i in range(joints)]
    s.tool_pose = [0.4, 0.1, 0.3, 0.0, 1.0, 0.0, 0.0]
    s.finger_width, s.finger_force, s.finger_width_target = 0.0412, 19.7, 0.03
    s.arm_command_id, s.arm_moving, s.arm_tracking_error = command, True, 0.002
    s.num_objects = objects
    for i in range(objects):
        o = sim_object_t()
        o.name = f"cube_{i}"
        o.pose = [0.1 * i, 0.2, 0.05, 0.0, 0.0, 0.0, 1.0]
        o.twist = [0.0, 0.01 * i, 0.0, 0.0, 0.0, -0.1]
        s.objects.append(o)
    s.num_contacts = contacts
    for i in range(contacts):
        c = sim_contact_t()
        c.body_a, c.body_b, c.points, c.normal_force = f"finger_{i}", "cube_0", 4, 9.5
        s.contacts.append(c)
    return s.encode()


def same(data: bytes, valid: bool = False) -> None:
    want = decode(sim_state_t, data)
    got = decode_sim_state(data)
    if want is None:
        assert got is None, data
        return
    assert got is not None, data
    same_stamp_and_fields(got, want, FIELDS)
    assert [fields(o, sim_object_t.__slots__) for o in got.objects] == \
        [fields(o, sim_object_t.__slots__) for o in want.objects]
    assert [fields(c, sim_contact_t.__slots__) for c in got.contacts] == \
        [fields(c, sim_contact_t.__slots__) for c in want.contacts]
    assert type(got.objects) is type(want.objects) and type(got.contacts) is type(want.contacts)
    if valid:
        assert got.encode() == data


@pytest.mark.parametrize("data", [state(), state(0, 0, 0), state(1, 1, 1, name="ß-gelenk", command=""),
                                  state(9, 12, 6, command="x" * 300)])
def test_valid_states_decode_alike(data):
    same(data, valid=True)
    assert decode_sim_state(data) is not None


def test_every_cut_and_growth_is_refused_alike():
    for data in cut_and_grown(state()):
        same(data)


def test_flipped_bytes_decode_alike():
    for data in flipped(state(), 20261207, 4000):
        same(data)


def count_at(data: bytes, which: str) -> int:
    """Where the state's object or contact count is (the states built above)."""
    s = decode(sim_state_t, data)
    head = 8 + 16 + 4 + len(s.header.sender) + 1 + 4
    joints = 4 + sum(4 + len(n.encode()) + 1 for n in s.joint_names) + 24 * s.num_joints
    arm = 56 + 24 + 4 + len(s.arm_command_id.encode()) + 1 + 1 + 8
    objects_at = head + joints + arm
    if which == "objects":
        return objects_at
    return objects_at + 4 + sum(4 + len(o.name.encode()) + 1 + 104 for o in s.objects)


@pytest.mark.parametrize("which", ["objects", "contacts"])
def test_odd_counts_decode_alike(which):
    data = state()
    at = count_at(data, which)
    assert struct.unpack_from(">i", data, at)[0] == (3 if which == "objects" else 2)
    for count in (-1, -(2 ** 31), 0, 1, 2 ** 31 - 1, 10_000):
        same(data[:at] + struct.pack(">i", count) + data[at + 4:])
    # A negative count reads no items, as the generated decoder does; what follows must
    # then end the message exactly.
    empty = state(8, 0, 0)
    at = count_at(empty, which)
    negative = empty[:at] + struct.pack(">i", -3) + empty[at + 4:]
    got = decode_sim_state(negative)
    assert got is not None and decode(sim_state_t, negative) is not None
    assert (got.num_objects if which == "objects" else got.num_contacts) == -3


def test_joint_counts_and_lengths_that_cannot_fit_are_refused_alike():
    data = state()
    at = 8 + 16 + 4 + 4 + 4  # fingerprint, frame and time, "sim\0", seq
    for count in (-1, -(2 ** 31), 2 ** 31 - 1, 100_000):
        same(data[:at] + struct.pack(">i", count) + data[at + 4:])
    same(data[:at + 4] + struct.pack(">I", 2 ** 32 - 1) + data[at + 8:])  # a name longer than the state
    bad_utf8 = bytearray(state(1, 1, 1, name="abc"))
    bad_utf8[bad_utf8.index(b"abc")] = 0xFF
    same(bytes(bad_utf8))
    assert decode_sim_state(bytes(bad_utf8)).joint_names == ["\ufffdbc_0"]


def test_forged_joint_counts_do_not_grow_the_decoders_structs():
    from skillbus import lcm_read

    data = state()
    at = 8 + 16 + 4 + 4 + 4
    before = len(lcm_read.DOUBLES)
    for count in range(1000, 1300):
        forged = data[:at] + struct.pack(">i", count) + (struct.pack(">I", 1) + b"\0") * count
        assert decode_sim_state(forged) is None
        assert decode(sim_state_t, forged) is None
    assert len(lcm_read.DOUBLES) <= before + 1


def test_states_whose_joint_names_change_are_read_anew():
    # The names' bytes are kept from the last state: states alternating two sets of names
    # of the same count and lengths must each give their own.
    first, second = state(name="joint"), state(name="jiont")
    assert len(first) == len(second)
    for data in (first, second, second, first, first[:40] + b"X" + first[41:]):
        same(data, valid=data in (first, second))
    assert decode_sim_state(second).joint_names[0] == "jiont_0"
    assert decode_sim_state(first).joint_names[0] == "joint_0"


def test_what_is_not_bytes_is_read_as_the_generated_decoder_reads_it():
    data = state()
    for other in (bytearray(data), memoryview(data)):
        got = decode_sim_state(other)
        assert got is not None and got.encode() == data
    for other in (data.decode("latin-1"), None, 7):
        assert decode_sim_state(other) is None and decode(sim_state_t, other) is None
