"""The console's managers: one that answers none of three probes in a row (and sends no
progress) is dropped, its running tasks lost; counted in probes, not in seconds, so that a
bus thread held by a long job (a slow /api/skills, a paged search) drops no live manager.
Before, a wall-clock age was checked right after each probe, before its answers could be
read: a job of six seconds dropped every manager and failed their running tasks. The
console's LiveSkills on a stand-in bus (a unit test)."""

from __future__ import annotations

from skillbus.console import live
from skillbus.console.live import LiveSkills
from skillbus.msgs import skill_manager_info_t, skill_node_progress_t, skill_progress_t
from support.stand_in_bus import StandInBus


def announce(skills: LiveSkills, incarnation: int = 1) -> None:
    info = skill_manager_info_t()
    info.name, info.incarnation = "skill_mgr", incarnation
    info.header.sender = "skill_mgr"
    skills._on_manager("SB_MANAGERS", info.encode())


def progress(skills: LiveSkills, task: int = 1, tick: int = 1) -> None:
    p = skill_progress_t()
    p.task, p.tick, p.state = task, tick, 2  # Running
    n = skill_node_progress_t()
    n.id, n.parent, n.type, n.state = 0, -1, "Wait", 2
    p.nodes, p.num_nodes = [n], 1
    skills._on_progress("", p.encode())
    skills.flush()


def test_a_manager_is_dropped_after_three_unanswered_probes_whatever_the_time(monkeypatch):
    now = [0.0]
    monkeypatch.setattr(live.time, "monotonic", lambda: now[0])
    events: list[dict] = []
    skills = LiveSkills(StandInBus(), events.append)
    announce(skills)
    progress(skills)
    now[0] += 60.0  # (a bus thread held for a minute: no probe went out meanwhile)
    skills.probe()
    assert "" in skills.managers
    for _ in range(2):  # answered: kept
        skills.probe()
        announce(skills)
    for _ in range(3):  # silent, but its progress comes: kept
        skills.probe()
        progress(skills, tick=5)
    assert "" in skills.managers and skills.trees.get("", 1).state == "Running"
    for _ in range(3):  # three probes unanswered, no progress
        skills.probe()
    assert "" in skills.managers  # (the third may still be answered)
    skills.probe()
    assert "" not in skills.managers
    tree = skills.trees.get("", 1)
    assert tree.state == "Failure" and "has not answered for 9 s (3 probes)" in tree.message, tree
