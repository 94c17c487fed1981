"""sim_state_t decoded straight from its bytes.

The simulated gripper device reads the physics server's state at every frame while its
fingers move or hold an object (most of the demo's frames): LCM's generated Python took
about 55 µs a state there, a fifth of the device's time in a frame (docs/benchmarks.md).
This decoder reads the same layout with skillbus.lcm_read and gives the same message (the
same field values and types: tuples for the arrays, lists of sim_object_t and
sim_contact_t, strings decoded with 'replace' less their last byte), or None for exactly
the bytes `skillbus.msgs.decode` refuses. Like the generated decoder it takes a negative
object or contact count as no objects or contacts (the count kept as it came): the tests
compare the two on valid, cut and corrupted states.
"""

from __future__ import annotations

import struct

from skillbus import lcm_read
from skillbus.msgs import header_t, sim_contact_t, sim_object_t, sim_state_t

_FINGERPRINT = sim_state_t._get_packed_fingerprint()
_FINGERS = struct.Struct(">7dddd")  # tool_pose, finger_width, finger_force, finger_width_target
_ARM_TAIL = struct.Struct(">bdi")  # arm_moving, arm_tracking_error, num_objects
_OBJECT = struct.Struct(">7d6d")  # pose, twist
_CONTACT = struct.Struct(">id")  # points, normal_force
# The fewest bytes an object and a contact take (empty names): a count that cannot fit is
# refused before anything is built for it.
_OBJECT_MIN = 4 + _OBJECT.size
_CONTACT_MIN = 8 + _CONTACT.size

_new_state, _new_header = sim_state_t.__new__, header_t.__new__
_new_object, _new_contact = sim_object_t.__new__, sim_contact_t.__new__
_string, _doubles, _INT = lcm_read.string, lcm_read.doubles, lcm_read.INT


_JOINT_NAMES = lcm_read.RepeatedStrings()


def decode_sim_state(data: bytes) -> sim_state_t | None:
    """The sim_state_t `data` encodes, or None when skillbus.msgs.decode would refuse it."""
    try:
        head = lcm_read.joints_head(data, _FINGERPRINT, _JOINT_NAMES, 28)  # (a name and three numbers a joint)
        if head is None:
            return None
        data, end, stamp, n, names, at = head
        joints = _doubles(n)
        position = joints.unpack_from(data, at)
        velocity = joints.unpack_from(data, at + joints.size)
        effort = joints.unpack_from(data, at + 2 * joints.size)
        fingers = _FINGERS.unpack_from(data, at + 3 * joints.size)
        command_id, at = _string(data, at + 3 * joints.size + _FINGERS.size, end)
        moving, tracking_error, num_objects = _ARM_TAIL.unpack_from(data, at)
        at += _ARM_TAIL.size
        if num_objects * _OBJECT_MIN > end - at:
            return None
        objects = []
        for _ in range(num_objects):  # (none for a negative count, as the generated decoder)
            o = _new_object(sim_object_t)
            o.name, at = _string(data, at, end)
            numbers = _OBJECT.unpack_from(data, at)
            at += _OBJECT.size
            o.pose, o.twist = numbers[:7], numbers[7:]
            objects.append(o)
        (num_contacts,) = _INT.unpack_from(data, at)
        at += 4
        if num_contacts * _CONTACT_MIN > end - at:
            return None
        contacts = []
        for _ in range(num_contacts):
            c = _new_contact(sim_contact_t)
            c.body_a, at = _string(data, at, end)
            c.body_b, at = _string(data, at, end)
            c.points, c.normal_force = _CONTACT.unpack_from(data, at)
            at += _CONTACT.size
            contacts.append(c)
    except (struct.error, lcm_read.CutShort):
        return None
    if at != end:
        return None
    h = _new_header(header_t)
    h.frame, h.sim_time_ns, h.sender, h.seq = stamp
    s = _new_state(sim_state_t)
    s.header, s.num_joints, s.joint_names = h, n, names
    s.position, s.velocity, s.effort = position, velocity, effort
    s.tool_pose = fingers[:7]
    s.finger_width, s.finger_force, s.finger_width_target = fingers[7:]
    s.arm_command_id, s.arm_moving, s.arm_tracking_error = command_id, bool(moving), tracking_error
    s.num_objects, s.objects, s.num_contacts, s.contacts = num_objects, objects, num_contacts, contacts
    return s
