"""skillbus.can.pdo_codec against python-canopen's own PDO variable reads and writes: the
same bytes and values for the gripper's TPDO1, and canopen's path kept for any map it
cannot do byte for byte."""

from __future__ import annotations

import random

import canopen
import pytest

from skillbus.can.eds import EDS, TPDO1_FIELDS
from skillbus.can.pdo_codec import PdoCodec


@pytest.fixture
def tpdo():
    net = canopen.Network()
    node = canopen.RemoteNode(5, str(EDS))
    net.add_node(node)
    node.tpdo.read(from_od=True)
    return node.tpdo[1]


def test_reads_and_writes_what_canopen_reads_and_writes(tpdo):
    codec = PdoCodec.of(tpdo, TPDO1_FIELDS)
    assert codec is not None and codec.size == 7
    rng = random.Random(7)
    for _ in range(200):
        values = (rng.randrange(0, 1 << 16), rng.randrange(-(1 << 31), 1 << 31), rng.randrange(0, 256))
        for name, v in zip(TPDO1_FIELDS, values):
            tpdo[name].raw = v
        by_canopen = bytes(tpdo.data)
        tpdo.data[:] = bytes(7)
        codec.write(tpdo, values)
        assert bytes(tpdo.data) == by_canopen
        assert codec.read(tpdo.data) == tuple(tpdo[name].raw for name in TPDO1_FIELDS) == values


def test_out_of_range_values_fail_as_canopens_do(tpdo):
    codec = PdoCodec.of(tpdo, TPDO1_FIELDS)
    for bad in ((1 << 16, 0, 0), (0, 1 << 31, 0), (0, 0, 256)):
        with pytest.raises((ValueError, OverflowError)):
            codec.write(tpdo, bad)
    with pytest.raises(ValueError):
        codec.read(bytes(6))  # shorter than the map


def test_a_map_it_cannot_do_byte_for_byte_is_left_to_canopen(tpdo):
    assert PdoCodec.of(tpdo, ("Statusword", "Grip state", "Position actual value")) is None  # another order
    assert PdoCodec.of(tpdo, TPDO1_FIELDS[:2]) is None
    tpdo.map[2].length = 4  # (a variable that fills half a byte)
    assert PdoCodec.of(tpdo, TPDO1_FIELDS) is None
