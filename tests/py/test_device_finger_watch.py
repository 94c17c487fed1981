"""GripperDevice.finger_watch: the bounds under which the lockstep device holding an object
lets the quiet-frame core ack its frames (common/python/finger_watch.hpp), and when it
gives none. The core's use of them is tests/py/test_finger_watch.py; whole sessions holding
a cube, with and without the core, tests/integration/test_gripper_lockstep.py."""

from __future__ import annotations

import canopen
import pytest

from skillbus.can import cia402 as c
from skillbus.can.device import EDS, RATED_FORCE, GripperDevice
from skillbus.can.fingers import AT_TARGET_UM, MAX_FORCE_N, MAX_WIDTH_UM, WIDTH_SLACK_UM, SimFingers


@pytest.fixture
def holding():
    """A device in operation whose fingers closed towards 10 mm with 20 N and stalled on a
    5 cm cube, TPDO1 last sent at 50.000 mm, three frames ago."""
    fingers = SimFingers(lambda m: None)
    dev = GripperDevice(canopen.Network(), 5, EDS, fingers=fingers)
    dev.event_every = 10
    dev.state = c.OPERATION_ENABLED
    dev.node.sdo[0x6073].raw = 200
    fingers.move_to(10_000, 50_000, 200)
    fingers.on_state(0.05, 19.5, {"cube"}, 0.01, 1.0)
    fingers.step(0.02)
    assert fingers.moving and fingers.in_contact
    dev._last_sent, dev._since_sent = (0, 50_000, dev.grip_state()), 3
    return dev, fingers


def test_holding_steady_the_watch_is_the_devices_own_rules(holding):
    dev, _ = holding
    lo, hi = -WIDTH_SLACK_UM * 1e-6, (MAX_WIDTH_UM + WIDTH_SLACK_UM) * 1e-6
    assert dev.finger_watch() == (lo, hi, 0.9 * 20.0, MAX_FORCE_N, 49_951, 50_049, 10_000.0, float(AT_TARGET_UM))
    # and the frames until TPDO1's event timer are quiet, as at rest (no heartbeat here:
    # the node has not booted)
    assert dev.quiet_horizon(100) == (106, 2**63 - 1)


def test_a_force_limit_at_which_the_block_becomes_a_fault_gets_no_watch(holding):
    dev, _ = holding
    dev.node.sdo[0x6073].raw = RATED_FORCE + 1
    assert dev.finger_watch() is None


@pytest.mark.parametrize("why", ["not touching", "no TPDO1 yet", "TPDO1 due", "not in operation", "at the target"])
def test_no_watch_where_the_next_frame_may_change_what_it_reports(holding, why):
    dev, fingers = holding
    if why == "not touching":
        fingers.on_state(0.05, 19.5, set(), 0.01, 1.0)
    elif why == "no TPDO1 yet":
        dev._last_sent = None
    elif why == "TPDO1 due":
        dev._since_sent = dev.event_every
    elif why == "not in operation":
        dev.state = c.SWITCHED_ON
    else:
        fingers.on_state(0.0101, 19.5, {"cube"}, 0.01, 1.0)  # (within 500 µm of it: not stalled)
    assert dev.finger_watch() is None


def test_moving_fingers_touching_nothing_have_no_horizon(holding):
    dev, fingers = holding
    fingers.on_state(0.03, 0.5, set(), 0.01, 1.0)  # closing freely
    assert fingers.moving and not fingers.in_contact
    assert dev.quiet_horizon(100) is None
