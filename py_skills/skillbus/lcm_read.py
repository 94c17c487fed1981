"""Reading LCM's encoding straight from a message's bytes, for the decoders of the messages
read every frame (skillbus.robot.arm_state_decode, skillbus.sim.state_decode).

LCM's generated Python decodes through a BytesIO, a struct format built per array and a
read per field. These read the same layout with precompiled structs at offsets, and keep
the generated decoder's quirks, so that a decoder built on them gives the same message,
or refuses exactly what skillbus.msgs.decode refuses.
"""

from __future__ import annotations

import struct

LENGTH = struct.Struct(">I")
INT = struct.Struct(">i")
TIMES = struct.Struct(">qq")
POSE = struct.Struct(">7d")
# A struct per array length, kept for the lengths that come (a decoder checks a count
# against the bytes left before it asks); at most DOUBLES_KEPT of them, so that messages
# with ever new counts that fit cannot grow it: past that a struct is made for the call.
DOUBLES: dict[int, struct.Struct] = {}
DOUBLES_KEPT = 64


def doubles(n: int) -> struct.Struct:
    s = DOUBLES.get(n)
    if s is None:
        s = struct.Struct(f">{n}d")
        if len(DOUBLES) < DOUBLES_KEPT:
            DOUBLES[n] = s
    return s


class CutShort(Exception):
    """A string's length runs past the message's end."""


def string(data: bytes, at: int, end: int) -> tuple[str, int]:
    """The LCM string at `at` and the position after it. Its length counts the NUL, which
    is dropped as LCM's Python drops the last byte, whatever it is; bytes that are not
    UTF-8 are replaced, as there."""
    (size,) = LENGTH.unpack_from(data, at)
    at += 4
    if at + size > end:
        raise CutShort
    return data[at:at + size][:-1].decode("utf-8", "replace"), at + size


def message_bytes(data: object) -> bytes | None:
    """`data` as bytes where skillbus.msgs.decode reads it (bytes, a bytearray, a
    memoryview); None for anything else, which it refuses."""
    if type(data) is bytes:
        return data
    return bytes(data) if isinstance(data, (bytearray, memoryview)) else None


_STAMP_COUNT = struct.Struct(">ii")


def stamp_and_count(data: bytes, end: int) -> tuple[int, int, str, int, int, int]:
    """The header_t after a message's fingerprint and the int32 count after it: (frame,
    sim_time_ns, sender, seq, count, the position after the count). struct.error or
    CutShort when the message ends first."""
    frame, sim_time_ns = TIMES.unpack_from(data, 8)
    sender, at = string(data, 24, end)
    seq, count = _STAMP_COUNT.unpack_from(data, at)
    return frame, sim_time_ns, sender, seq, count, at + 8


def joints_head(data: object, fingerprint: bytes, names: "RepeatedStrings",
                min_per_joint: int) -> tuple[bytes, int, tuple[int, int, str, int], int, list[str], int] | None:
    """What a robot's state messages begin with (robot_arm_state_t, sim_state_t): the
    fingerprint, the header_t, the joint count and the joint names. (data as bytes, its
    end, (frame, sim_time_ns, sender, seq), the count, the names, the position after
    them), or None for what skillbus.msgs.decode refuses there: not bytes, another type,
    a negative count, or one whose joints could not fit (`min_per_joint` bytes each).
    struct.error or CutShort when the message ends first."""
    data = message_bytes(data)
    if data is None or data[:8] != fingerprint:
        return None
    end = len(data)
    frame, sim_time_ns, sender, seq, n, at = stamp_and_count(data, end)
    if n < 0 or min_per_joint * n > end - at:
        return None
    joint_names, at = names.read(data, at, end, n)
    return data, end, (frame, sim_time_ns, sender, seq), n, joint_names, at


class RepeatedStrings:
    """A run of LCM strings that comes the same message after message (a robot's joint
    names): the bytes and strings of the last run read, compared (a bytes comparison)
    before they are decoded again. One per decoder; a hit gives a new list, as the
    generated decoder does."""

    def __init__(self) -> None:
        self._last: list = [b"", []]  # (swapped whole: a read of it is one step under the GIL)

    def read(self, data: bytes, at: int, end: int, n: int) -> tuple[list[str], int]:
        """The `n` strings at `at` and the position after them (CutShort, struct.error
        when the message ends first)."""
        raw, strings = self._last
        size = len(raw)
        if size and len(strings) == n and data[at:at + size] == raw:
            return list(strings), at + size
        start, strings = at, []
        unpack = LENGTH.unpack_from
        for _ in range(n):
            (length,) = unpack(data, at)
            at += 4
            if at + length > end:
                raise CutShort
            strings.append(data[at:at + length][:-1].decode("utf-8", "replace"))
            at += length
        self._last = [data[start:at], strings]
        return list(strings), at
