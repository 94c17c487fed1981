"""robot_arm_state_t decoded straight from its bytes.

A skill that moves the arm reads its state at every tick (Arm.state), and LCM's generated
Python decodes it through a BytesIO, a struct format built per array and a read per field:
about a fifth of a motion skill's tick in the demo. This decoder reads the same layout
with precompiled structs at offsets and gives the same message (the same field values
and types: tuples for the arrays, strings decoded with 'replace' less their last byte),
or None for exactly the bytes `skillbus.msgs.decode` refuses (a wrong fingerprint, a
message cut short or longer than its fields, a negative count): the tests compare the two
on valid, cut and corrupted messages.
"""

from __future__ import annotations

import struct

from skillbus import lcm_read
from skillbus.msgs import header_t, robot_arm_state_t

_FINGERPRINT = robot_arm_state_t._get_packed_fingerprint()
_POSE, _doubles, _DOUBLES = lcm_read.POSE, lcm_read.doubles, lcm_read.DOUBLES
_JOINT_NAMES = lcm_read.RepeatedStrings()
_TAIL = struct.Struct(">bd")  # arm_moving, arm_tracking_error
_CutShort, _string = lcm_read.CutShort, lcm_read.string


def decode_arm_state(data: bytes) -> robot_arm_state_t | None:
    """The robot_arm_state_t `data` encodes, or None when skillbus.msgs.decode would
    refuse it."""
    try:
        head = lcm_read.joints_head(data, _FINGERPRINT, _JOINT_NAMES, 24)  # (three numbers a joint at least)
        if head is None:
            return None
        data, end, stamp, n, names, at = head
        doubles = _doubles(n)
        position = doubles.unpack_from(data, at)
        at += doubles.size
        velocity = doubles.unpack_from(data, at)
        at += doubles.size
        effort = doubles.unpack_from(data, at)
        at += doubles.size
        tool_pose = _POSE.unpack_from(data, at)
        command_id, at = _string(data, at + _POSE.size, end)
        moving, tracking_error = _TAIL.unpack_from(data, at)
        at += _TAIL.size
    except (struct.error, _CutShort):
        return None
    if at != end:
        return None
    h = header_t()
    h.frame, h.sim_time_ns, h.sender, h.seq = stamp
    s = robot_arm_state_t()
    s.header, s.num_joints, s.joint_names = h, n, names
    s.position, s.velocity, s.effort, s.tool_pose = position, velocity, effort, tool_pose
    s.arm_command_id, s.arm_moving, s.arm_tracking_error = command_id, bool(moving), tracking_error
    return s
