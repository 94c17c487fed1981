"""A Python participant on the wall clock (LockstepParticipant(wall_clock=True)) after a
long frame: the frames it missed are not run back to back; its schedule starts again from
the late frame, at the frame period (as the C++ participant's:
tests/cpp/test_lockstep_frame.cpp)."""

from __future__ import annotations

import time

from skillbus.bus import open_bus
from skillbus.lockstep import LockstepParticipant


def test_after_a_long_frame_the_missed_frames_are_not_run_back_to_back():
    p = LockstepParticipant(open_bus("memq://"), "p", wall_clock=True, wall_frame_period_ns=20_000_000, wall_frames=8)
    at: list[float] = []

    def on_frame(frame: int, sim_time_ns: int) -> None:
        at.append(time.monotonic())
        assert sim_time_ns == frame * 20_000_000  # (sim time stays the frame's)
        if frame == 2:
            time.sleep(0.2)  # ten frames' time

    p.on_frame = on_frame
    r = p.run()
    assert r.ok and r.frames == 8 and len(at) == 8
    gaps = [b - a for a, b in zip(at[3:], at[4:])]
    assert min(gaps) >= 0.015, gaps
