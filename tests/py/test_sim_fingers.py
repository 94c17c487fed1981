"""The device's view of the physics fingers (SimFingers): set-points out, stall, grip,
following error, all from the width and force the physics server reports."""

import pytest

from skillbus.can.fingers import FOLLOWING_TIMEOUT_S, SimFingers


def make():
    sent = []
    f = SimFingers(sent.append)
    f.on_state(0.08, 0.0, set())
    return f, sent


def test_a_set_point_becomes_a_physics_command_in_si_units():
    f, sent = make()
    f.move_to(30_000, 50_000, 200)
    assert len(sent) == 1
    assert (sent[0].width, sent[0].speed, sent[0].force_limit) == pytest.approx((0.03, 0.05, 20.0))
    assert f.moving


def test_reaching_the_target_ends_the_move():
    f, _ = make()
    f.move_to(30_000, 50_000, 200)
    f.on_state(0.0302, 0.0, set())
    f.step(0.01)
    assert not f.moving and not f.in_contact


def test_stalled_on_a_touched_object_is_gripped():
    f, _ = make()
    f.move_to(0, 50_000, 200)
    f.on_state(0.05, 19.5, {"green"})
    f.step(0.01)
    assert f.moving and f.stalled and f.in_contact and f.blocked_for > 0
    f.on_state(0.05, 19.5, set())  # stalled on something it does not touch: not a grip
    assert not f.in_contact
    f.on_state(0.05, 10.0, {"green"})  # touching but not squeezing yet
    assert not f.in_contact


def test_lagging_the_profile_without_a_stall_is_a_following_error():
    f, _ = make()
    f.move_to(0, 50_000, 200)  # 50 mm/s: after 0.3 s it should be at 65 mm
    t = 0.0
    while t < 0.3 + FOLLOWING_TIMEOUT_S:
        f.on_state(0.08, 2.0, set())  # stuck at 80 mm, pushing with only 2 N
        f.step(0.01)
        t += 0.01
    assert f.following_error()
    g, _ = make()
    g.move_to(0, 50_000, 200)
    for i in range(50):  # following the profile: no error
        g.on_state(0.08 - 0.05 * 0.01 * (i + 1), 5.0, set())
        g.step(0.01)
    assert not g.following_error()


def test_fingers_as_fast_as_a_slowed_physics_are_not_behind():
    """On the wall clock a loaded machine runs the physics slower than real time: the
    fingers move at the commanded speed in the physics' time and lag the device's own
    clock. Not a following error (it faulted the gripper in the fault suite's wall-clock
    trials); lagging in the physics' time still is."""
    def run(width_after):
        f = SimFingers(lambda m: None)
        f.on_state(0.08, 0.0, set(), 0.08, 0.0)
        f.move_to(0, 50_000, 200)
        sim = 0.0
        for i in range(100):  # 1 s of the device's time, the physics at a third of it
            sim += 0.01 / 3
            f.on_state(width_after(sim), 2.0, set(), 0.0, sim)
            f.step(0.01)
            if f.following_error():
                return True
        return False

    assert not run(lambda t: 0.08 - 0.05 * t)  # on the profile in physics time
    assert run(lambda t: 0.08)  # stuck: behind in physics time too


def test_a_physics_that_stands_still_is_a_following_error():
    """A paused (or hung) physics: its time does not move while the fingers should; as a
    motor that does not turn, a following error (not an endless wait)."""
    from skillbus.can.fingers import FROZEN_PHYSICS_S
    f = SimFingers(lambda m: None)
    f.on_state(0.08, 0.0, set(), 0.08, 5.0)
    f.move_to(0, 50_000, 200)
    t = 0.0
    while t < FROZEN_PHYSICS_S + FOLLOWING_TIMEOUT_S + 0.1:
        f.on_state(0.08, 0.0, set(), 0.0, 5.0)  # acknowledged, but time stands at 5.0 s
        f.step(0.01)
        t += 0.01
    assert f.following_error()
