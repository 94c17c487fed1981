"""The lockstep master of the system (sim_server) waits for a participant's ack at least as
long as that participant may legitimately spend in one frame: a skill manager waiting for a
compound's expansion (TaskPlan plans then, seconds on a busy machine: a TaskPlan test once
failed with "no ack for frame 0 from participant(s) skill_mgr within 5.0 s"), the map
inserting a depth capture."""

import pytest

from skillbus.system import programs, robots_programs


def option_values(argv: list[str], option: str) -> list[str]:
    return [argv[i + 1] for i, a in enumerate(argv) if a == option]


def allowances(sim_argv: list[str]) -> dict[str, int]:
    out = {}
    for item in option_values(sim_argv, "--ack-timeout-ms-of"):
        name, ms = item.split("=")
        out[name] = int(ms)
    return out


@pytest.mark.parametrize("make", [lambda d: programs(d, perception=True), lambda d: robots_programs(d)],
                         ids=["one robot with a camera", "two robots"])
def test_the_master_waits_for_each_manager_longer_than_its_expansion_may_take(tmp_path, make):
    progs = {p.name: p for p in make(tmp_path)}
    allowed = allowances(progs["sim"].argv)
    managers = [p for p in progs.values() if p.argv[0].endswith("skill_mgr")]
    assert managers
    for mgr in managers:
        name = option_values(mgr.argv, "--name")[0] if "--name" in mgr.argv else "skill_mgr"
        (expand_ms,) = option_values(mgr.argv, "--expand-timeout-ms")
        assert allowed[name] > int(expand_ms), (name, allowed)
    if "map" in progs:
        assert allowed["map"] >= 60_000


def test_without_lockstep_there_is_no_master_to_tell(tmp_path):
    progs = {p.name: p for p in programs(tmp_path, lockstep=False)}
    assert allowances(progs["sim"].argv) == {}
