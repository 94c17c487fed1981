"""Damaged copies of a message, for the tests that compare a decoder of our own with LCM's
generated one (it must refuse exactly what LCM's refuses, and read alike what it reads)."""

from __future__ import annotations

import random
from typing import Iterator


def cut_and_grown(data: bytes) -> Iterator[bytes]:
    """Every prefix of `data`, and `data` with bytes after its end."""
    for cut in range(len(data)):
        yield data[:cut]
    for extra in (b"\x00", b"\x00" * 8, b"junk"):
        yield data + extra


def flipped(data: bytes, seed: int, count: int) -> Iterator[bytes]:
    """`count` copies of `data` with one to three bytes set at random (seeded)."""
    rng = random.Random(seed)
    for _ in range(count):
        b = bytearray(data)
        for _ in range(rng.randint(1, 3)):
            b[rng.randrange(len(b))] = rng.randrange(256)
        yield bytes(b)


HEADER = ("frame", "sim_time_ns", "sender", "seq")


def fields(m, names) -> list:
    """(name, repr, type) of each field: how a decoded copy is compared with LCM's (repr: a
    flipped byte may make a NaN, which equals nothing)."""
    return [(f, repr(getattr(m, f)), type(getattr(m, f))) for f in names]


def same_stamp_and_fields(got, want, names) -> None:
    """`got` reads as `want`: its header and the fields `names`, value and type alike."""
    assert fields(got.header, HEADER) == fields(want.header, HEADER)
    assert fields(got, names) == fields(want, names)
