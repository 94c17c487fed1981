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
