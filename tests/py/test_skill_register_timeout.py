"""A skill process's registration gives up after the time it was given (skills-process
--register-timeout), not after the 2 s of one attempt's RPC call."""

import time

import pytest

from skillbus.bus import open_bus
from skillbus.skill.process import SkillProcess
from skillbus.waiting import WaitTimeout


def test_registration_gives_up_in_its_own_time():
    proc = SkillProcess(open_bus("memq://"), "lonely", [])  # no manager on this bus
    t = time.monotonic()
    with pytest.raises(WaitTimeout, match="registration with the skill manager"):
        proc.register(timeout=0.3)
    assert time.monotonic() - t < 1.5
