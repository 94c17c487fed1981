"""The gripper device's status in its object dictionary (what an SDO upload reads) is the
status it last reported, whichever of its entries changed: it writes only those that did
(holding an object, only the width)."""

from __future__ import annotations

from skillbus.can import cia402 as c


def uploaded(node) -> tuple[int, int, int]:
    return node.sdo[0x6041].raw, node.sdo[0x6064].raw, node.sdo[0x2000].raw


def test_an_upload_reads_the_status_after_each_kind_of_change(device_and_driver):
    dev, node = device_and_driver
    dev._publish_status(event=False)
    assert uploaded(node) == dev._last_written
    seen = []
    for width in (41_000.4, 41_000.6, 41_001.4, 41_001.4, 0.0):  # only the width moves
        dev.model.width = width
        dev._publish_status(event=False)
        assert uploaded(node) == dev._last_written == (dev._last_written[0], round(width), dev._last_written[2])
        seen.append(dev._last_written)
    assert len({s[0] for s in seen}) == 1  # (the statusword never changed meanwhile)
    dev.state = c.FAULT  # only the statusword moves
    dev._publish_status(event=False)
    assert uploaded(node) == dev._last_written and dev._last_written[0] != seen[-1][0]
    assert dev._last_written[1:] == seen[-1][1:]
