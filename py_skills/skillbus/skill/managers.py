"""Finding the skill managers on the bus: one per robot.

A client publishes on the shared ``SB_MANAGERS_PROBE``; every skill manager answers at
once on the shared ``SB_MANAGERS`` with a ``skill_manager_info_t`` that names its robot
(the namespace of its ``SKILL`` area: ``r2/SB_SKILL_REQ``), its name, its agent and how
many skills it has (skill_mgr/src/directory.hpp). ``skillbus skills`` lists every
manager found this way; ``skillbus run`` uses it to say which robots there are when the
one it was told to use does not answer.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from skillbus.channels import channel


@dataclass(frozen=True)
class ManagerInfo:
    robot: str        # "" for a manager without a robot name
    name: str
    agent: str        # the element id of the robot it drives ("" until known)
    incarnation: int
    num_skills: int


def discover(bus, wait: float = 0.6) -> list[ManagerInfo]:
    """The managers that answer a probe within `wait` seconds, one per robot (a manager
    that answered twice counts once: its latest answer), sorted by robot name. The probe
    goes out twice, at once and half-way, for a bus on which a new subscriber needs time
    to be matched (DDS discovery)."""
    from skillbus.msgs import decode, skill_manager_info_t
    found: dict[tuple[str, str], ManagerInfo] = {}

    def on_info(ch: str, data: bytes) -> None:
        m = decode(skill_manager_info_t, data)
        if m is None:
            return
        found[(m.robot, m.name)] = ManagerInfo(m.robot, m.name, m.agent, m.incarnation, m.num_skills)

    sub = bus.subscribe(channel("SB_MANAGERS"), on_info)
    try:
        probe = skill_manager_info_t()
        probe.header.frame = -1
        probe.header.sender = "probe"
        start = time.monotonic()
        bus.publish(channel("SB_MANAGERS_PROBE"), probe.encode())
        probed_again = False
        while (left := wait - (time.monotonic() - start)) > 0:
            if not probed_again and left < wait / 2:
                bus.publish(channel("SB_MANAGERS_PROBE"), probe.encode())
                probed_again = True
            bus.handle(min(left, 0.05))
    finally:
        bus.unsubscribe(sub)
    return sorted(found.values(), key=lambda m: (m.robot, m.name))


def robots_text(managers: list[ManagerInfo]) -> str:
    """'r1, r2' (a manager without a robot name is '(none)')."""
    return ", ".join(m.robot or "(none)" for m in managers) or "none"
