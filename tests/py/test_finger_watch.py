"""The quiet-frame core's finger watch (common/python/finger_watch.hpp): a frame whose
newest sim_state_t keeps the simulated fingers as the gripper device holding an object last
judged them is acked without Python; any other goes to Python with its clock and messages.
The core's verdict is compared with the device's own rules in Python (SimFingers'
stalled/in_contact, sim_state_reading, TPDO1's position delta) on states at and around
every bound; the device holding a cube through whole sessions, both ways, is
tests/integration/test_gripper_lockstep.py."""

from __future__ import annotations

import math
import random

import pytest

from skillbus.can.fingers import AT_TARGET_UM, MAX_FORCE_N, MAX_WIDTH_UM, WIDTH_SLACK_UM, sim_state_reading
from skillbus.msgs import header_t, sim_contact_t, sim_state_t
from skillbus.validate import BadValue
from test_quiet_frames_core import CLOCK, Rig, clock, count

STATE = "SB_SIM_STATE"
SENT, DELTA = 50_000, 50          # TPDO1 last sent at 50.000 mm; 0x2001 = 50 µm
TARGET_UM, LIMIT_N = 10_000.0, 20.0  # closing to 10 mm with 20 N: stalled on a 5 cm cube
LO, HI = -WIDTH_SLACK_UM * 1e-6, (MAX_WIDTH_UM + WIDTH_SLACK_UM) * 1e-6
WATCH = (LO, HI, 0.9 * LIMIT_N, MAX_FORCE_N, SENT - DELTA + 1, SENT + DELTA - 1, TARGET_UM, float(AT_TARGET_UM))


def state(frame: int, width_m=0.05, force_n=19.5, target_m=0.01, contacts=1) -> bytes:
    s = sim_state_t()
    s.header = header_t()
    s.header.frame, s.header.sim_time_ns, s.header.sender, s.header.seq = frame, frame * 10_000_000, "sim", 0
    s.tool_pose = [0.0] * 6 + [1.0]
    s.finger_width, s.finger_force, s.finger_width_target = width_m, force_n, target_m
    for i in range(contacts):
        c = sim_contact_t()
        c.body_a, c.body_b, c.points, c.normal_force = "finger", f"cube{i}", 1, 5.0
        s.contacts.append(c)
    s.num_contacts = len(s.contacts)
    return s.encode()


def python_says_quiet(width_m, force_n, target_m, contacts) -> bool:
    """The device's own rules: a state it would take (sim_state_reading), fingers stalled on
    something (SimFingers.stalled, in_contact) and no TPDO1 due (GripperDevice._changed_enough)."""
    s = sim_state_t()
    s.header = header_t()
    s.finger_width, s.finger_force, s.finger_width_target = width_m, force_n, target_m
    try:
        width, force, _, target, _ = sim_state_reading(s)
    except BadValue:
        return False
    width_um = width * 1e6
    acknowledged = abs(target * 1e6 - TARGET_UM) < 1.0
    stalled = acknowledged and abs(width_um - TARGET_UM) > AT_TARGET_UM and force >= 0.9 * LIMIT_N
    return stalled and contacts > 0 and abs(int(round(width_um)) - SENT) < max(1, DELTA)


@pytest.fixture(params=["open", "signed"])
def rig(request):
    from test_quiet_frames_core import KEY
    r = Rig(keys=[KEY] if request.param == "signed" else [])
    r.core.set_subscribed(["SB_HEARD", STATE])
    r.core.set_latest_only([STATE])
    yield r
    r.close()


def frame_with(rig, frame: int, payload: bytes) -> tuple[int, list]:
    """Frame `frame` announcing one state of the frame before; the core's acks and hand-over."""
    rig.send(STATE, payload)
    rig.send(CLOCK, clock(frame, counts=[count("sim", STATE, frame - 1)]))
    acked, handed = 0, []
    for _ in range(10):
        rig.core.set_finger_watch(STATE, *WATCH)
        _, _, n, _ = rig.wait(0.1)
        acked += n
        handed += rig.handed
        if n or any(kind == 1 for kind, _, _ in rig.handed):
            break
    return acked, handed


def test_states_that_keep_the_fingers_as_they_were_are_acked_and_the_newest_handed_back(rig):
    payloads = [state(f, width_m=0.05 + f * 1e-6) for f in range(3)]  # a few µm a frame: no TPDO
    assert all(python_says_quiet(0.05 + f * 1e-6, 19.5, 0.01, 1) for f in range(3))
    acked = 0
    for f in range(1, 4):
        n, handed = frame_with(rig, f, payloads[f - 1])
        acked += n
        assert handed == [(0, STATE, payloads[f - 1])]
    assert acked == 3 and rig.last_acked == 3


BROKEN = {
    "moved enough for TPDO1": dict(width_m=(SENT + DELTA) * 1e-6),
    "moved the other way": dict(width_m=(SENT - DELTA) * 1e-6),
    "pushing less (slipping)": dict(force_n=0.9 * LIMIT_N - 0.01),
    "no contact (lost it)": dict(contacts=0),
    "another set-point": dict(target_m=0.02),
    "at the set-point": dict(width_m=0.0101, target_m=0.01),
    "width not a number": dict(width_m=math.nan),
    "force not a number": dict(force_n=math.nan),
    "force beyond any reading": dict(force_n=1e300),
    "set-point beyond the travel": dict(target_m=HI + 1e-6),
}


@pytest.mark.parametrize("why", BROKEN)
def test_a_state_that_breaks_the_watch_hands_python_the_frame(rig, why):
    payload = state(0, **BROKEN[why])  # (frame 1 announces frame 0's state)
    kw = {"width_m": 0.05, "force_n": 19.5, "target_m": 0.01, "contacts": 1, **BROKEN[why]}
    assert not python_says_quiet(**kw)
    acked, handed = frame_with(rig, 1, payload)
    assert acked == 0 and rig.last_acked == 0
    assert sorted(handed) == sorted([(1, CLOCK, clock(1, counts=[count("sim", STATE, 0)])), (2, STATE, payload)])


@pytest.mark.parametrize("how", ["cut", "grown"])
def test_a_state_that_does_not_decode_goes_to_python(rig, how):
    # (Python's decoder refuses both: a state cut short, and one with bytes after its end)
    payload = state(0)[:-12] if how == "cut" else state(0) + b"\0"
    from skillbus.sim.state_decode import decode_sim_state
    assert decode_sim_state(payload) is None
    acked, handed = frame_with(rig, 1, payload)
    assert acked == 0 and (2, STATE, payload) in handed


def test_the_core_decides_as_the_device_would_on_states_around_every_bound(rig):
    rng = random.Random(11)
    frame = 0
    for _ in range(300):
        width_um = rng.choice([SENT + DELTA - 0.5, SENT - DELTA + 0.5, SENT + DELTA - 1.5, SENT - DELTA + 1.5,
                               TARGET_UM + AT_TARGET_UM, SENT + rng.uniform(-60, 60)])
        force = rng.choice([0.9 * LIMIT_N, math.nextafter(0.9 * LIMIT_N, 0), LIMIT_N, rng.uniform(17.5, 18.5)])
        target_um = rng.choice([TARGET_UM, TARGET_UM + 0.999, TARGET_UM - 1.0, TARGET_UM + rng.uniform(-2, 2)])
        contacts = rng.choice([0, 1, 2])
        frame += 1
        payload = state(frame - 1, width_um * 1e-6, force, target_um * 1e-6, contacts)
        acked, handed = frame_with(rig, frame, payload)
        expected = python_says_quiet(width_um * 1e-6, force, target_um * 1e-6, contacts)
        assert (acked == 1) == expected, (width_um, force, target_um, contacts)
        if not expected:  # (Python took the frame: it acks it itself)
            rig.last_acked, rig.sim_time = frame, frame * 10_000_000
