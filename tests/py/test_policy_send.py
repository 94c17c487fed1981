"""Sending what the bus policy forbids fails at the sender, naming the rule it lacks:
every receiver would drop the message, and under lockstep the frame would wait for it
and fail as "message lost" (which is how a missing rule for the cameras first showed)."""

from __future__ import annotations

import secrets

import pytest

from skillbus.bus import AuthenticatedBus, BusError, open_raw_bus
from skillbus.policy import Policy


def bus_for(identity: str) -> AuthenticatedBus:
    rules = Policy.parse("SB_CAMERA_CLOUD sim\nSB_*_REQ *\n", "deploy/policy.conf")
    return AuthenticatedBus(open_raw_bus("memq://"), [secrets.token_bytes(32)], identity, rules)


def test_a_forbidden_send_fails_naming_the_policy_identity_and_channel():
    skills = bus_for("skills")
    skills.publish("SB_WM_REQ", b"ok")  # anyone may ask a server
    with pytest.raises(BusError) as e:
        skills.publish("SB_CAMERA_CLOUD", b"no")
    assert str(e.value) == ("the bus policy deploy/policy.conf does not let 'skills' send on SB_CAMERA_CLOUD: every "
                            "receiver would drop it (add a rule for it; docs/security.md)")
    with pytest.raises(BusError):
        skills.publish("SB_NOBODY", b"no")  # no rule: refused
    bus_for("sim").publish("SB_CAMERA_CLOUD", b"ok")


def test_without_a_policy_anything_signed_may_be_sent():
    AuthenticatedBus(open_raw_bus("memq://"), [secrets.token_bytes(32)], "x").publish("SB_ANY", b"ok")
