"""The lockstep CAN link names a CAN hub that went away when announced frames never
arrive (unit test: a stand-in participant and a stand-in bus; the real hub, device and
lockstep run in the fault suite)."""

from __future__ import annotations

import types

import pytest

from skillbus.can.lockstep_link import LockstepCanLink
from skillbus.lockstep import LockstepError


class QuietBus:
    """A CAN bus on which nothing arrives; `hub_losses` as the virtual SocketCAN bus counts."""

    def __init__(self) -> None:
        self.hub_losses = 0
        self.last_loss_at = None
        self.fault = None
        self.path = "/run/skillbus/gripper0.sock"

    def recv(self, timeout):
        return None

    def shutdown(self) -> None:
        pass


def link(bus: QuietBus) -> LockstepCanLink:
    participant = types.SimpleNamespace(subscribe=lambda *a, **k: None)
    network = types.SimpleNamespace(bus=None, notify=lambda *a: None)
    return LockstepCanLink(participant, bus, "gripper0.sock", network, set(), timeout=0.2)


def test_frames_lost_after_the_hub_went_away_name_the_hub():
    bus = QuietBus()
    lk = link(bus)
    try:
        lk._expected = [("gripper", 1)]
        bus.hub_losses += 1  # the hub died (and may be back): what was in flight is gone
        with pytest.raises(LockstepError, match=r"CAN frames lost on gripper0.sock: gripper announced 1 in frame 4, "
                                                r"0 arrived .*CAN hub gone: /run/skillbus/gripper0.sock"):
            lk.begin_frame(5)
    finally:
        lk.shutdown()


def test_frames_lost_with_the_hub_there_all_along_do_not_blame_it():
    bus = QuietBus()
    lk = link(bus)
    try:
        lk._expected = [("gripper", 1)]
        with pytest.raises(LockstepError) as e:
            lk.begin_frame(5)
        assert "hub" not in str(e.value)
    finally:
        lk.shutdown()


def test_frames_lost_soon_after_a_hub_loss_this_process_already_recovered_from_name_the_hub():
    # This process lost the hub and reconnected frames ago, but the sender had not: its
    # frame went nowhere (the fault suite's can_hub trial under lockstep).
    import time
    bus = QuietBus()
    lk = link(bus)
    try:
        bus.hub_losses += 1
        bus.last_loss_at = time.monotonic()
        lk.begin_frame(3)  # (nothing expected: the frame passes, and the loss is "seen")
        lk._expected = [("gripper", 1)]
        with pytest.raises(LockstepError, match=r"CAN hub gone: /run/skillbus/gripper0.sock"):
            lk.begin_frame(5)
        bus.last_loss_at = time.monotonic() - 60  # long ago: not blamed
        lk._expected = [("gripper", 1)]
        with pytest.raises(LockstepError) as e:
            lk.begin_frame(6)
        assert "hub" not in str(e.value)
    finally:
        lk.shutdown()
