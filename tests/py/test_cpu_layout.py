"""skillbus.cpu_layout: the physics server on a core of its own, every other program on
the rest, or nothing changed, saying why; a core that cannot be used is refused, naming
the ones that can."""

from __future__ import annotations

import pytest

from skillbus.cpu_layout import ACK_POLL_US, LayoutError, place
from skillbus.system import Program

PROGS = [Program("can_hub", ["hub"]), Program("sim", ["sim_server", "--pipeline"]), Program("wm", ["wm_server"]),
         Program("skills", ["python", "-m", "skillbus.cli", "skills-process"], participant=True)]
TASKSET = "/usr/bin/taskset"
CHRT = "/usr/bin/chrt"
BATCH = [CHRT, "--batch", "0"]


def prefixes(layout):
    return {p.name: p.argv[:3] for p in layout.programs}


POLL = ["--ack-poll-us", str(ACK_POLL_US)]
LATENCY = ["--cpu-latency-us", "0"]


@pytest.fixture
def device(tmp_path):
    """A file this process may write, standing for the kernel's CPU latency device."""
    path = tmp_path / "cpu_dma_latency"
    path.write_bytes(b"")
    return str(path)


def commands(layout):
    """Each program's command after its placement's prefix (and before the physics server's
    options)."""
    return [p.argv[3:len(p.argv) - len(layout.physics_options)] if p.name == "sim" else p.argv[6:]
            for p in layout.programs]


def test_auto_gives_the_physics_the_last_core_and_the_others_the_rest_under_the_batch_policy(device):
    two = place(PROGS, "auto", {0, 1}, taskset=TASKSET, chrt=CHRT, latency_device=device)
    assert prefixes(two) == {"can_hub": [TASKSET, "--cpu-list", "0"], "sim": [TASKSET, "--cpu-list", "1"],
                             "wm": [TASKSET, "--cpu-list", "0"], "skills": [TASKSET, "--cpu-list", "0"]}
    # The others wait for the running one to block instead of preempting it; the physics
    # server, alone on its core, keeps the normal policy.
    assert {p.name: p.argv[3:6] == BATCH for p in two.programs} == {"can_hub": True, "sim": False, "wm": True,
                                                                     "skills": True}
    assert commands(two) == [p.argv for p in PROGS]  # the commands themselves unchanged
    # Alone on its core, the physics server polls for the acks instead of sleeping, and
    # asks for idle cores that poll while it runs.
    assert two.physics_options == POLL + LATENCY
    assert {p.name: p.argv[-4:] == POLL + LATENCY for p in two.programs} == {"can_hub": False, "sim": True,
                                                                             "wm": False, "skills": False}
    assert 0 < ACK_POLL_US <= 5000  # a frame's acks, not a stalled participant's
    assert two.others == {0}
    assert two.note == ("the physics server on core 1 (polling for acks; idle cores polling), the other programs "
                        "on 0 (batch scheduling)")
    four = place(PROGS, "auto", {0, 2, 5, 7}, taskset=TASKSET, chrt=CHRT)
    assert prefixes(four)["sim"][2] == "7" and prefixes(four)["wm"][2] == "0,2,5"
    assert [p.participant for p in four.programs] == [p.participant for p in PROGS]


def test_a_named_core():
    layout = place(PROGS, " 0 ", {0, 1}, taskset=TASKSET)
    assert prefixes(layout)["sim"][2] == "0" and prefixes(layout)["skills"][2] == "1"


def test_nothing_changes_when_off_with_one_core_or_without_taskset():
    for layout in (place(PROGS, "off", {0, 1}, taskset=TASKSET), place(PROGS, "auto", {3}, taskset=TASKSET)):
        assert layout.programs == PROGS and layout.others is None
    assert "left to the kernel" in place(PROGS, "OFF", {0, 1}).note
    assert "one usable core (3)" in place(PROGS, "auto", {3}).note
    assert place([p for p in PROGS if p.name != "sim"], "auto", {0, 1}, taskset=TASKSET).others is None


@pytest.mark.parametrize("choice, why", [
    ("2", r"--physics-core 2: not a core this process may use \(0,1\)"),
    ("-1", r"not a core this process may use \(0,1\)"),
    ("fast", r"--physics-core 'fast': 'auto', 'off' or a core's number \(this process may use 0,1\)"),
    ("", r"'auto', 'off' or a core's number"),
])
def test_a_core_that_cannot_be_used_is_refused_naming_the_usable_ones(choice, why):
    with pytest.raises(LayoutError, match=why):
        place(PROGS, choice, {0, 1}, taskset=TASKSET)


def test_the_only_usable_core_cannot_be_the_physics_own():
    with pytest.raises(LayoutError, match="the only core this process may use.*--physics-core off"):
        place(PROGS, "4", {4}, taskset=TASKSET)


def test_without_taskset_auto_changes_nothing_and_a_named_core_is_refused(monkeypatch):
    monkeypatch.setattr("skillbus.cpu_layout.shutil.which", lambda name: None)
    layout = place(PROGS, "auto", {0, 1})
    assert layout.programs == PROGS and "taskset (util-linux) is not installed" in layout.note
    with pytest.raises(LayoutError, match="--physics-core 1: taskset"):
        place(PROGS, "1", {0, 1})


def test_without_chrt_the_programs_are_placed_and_the_note_says_what_is_missing(monkeypatch):
    monkeypatch.setattr("skillbus.cpu_layout.shutil.which", lambda name: None if name == "chrt" else TASKSET)
    layout = place(PROGS, "auto", {0, 1})
    assert prefixes(layout)["wm"] == [TASKSET, "--cpu-list", "0"]
    assert [p.argv[3:len(p.argv) - len(layout.physics_options)] if p.name == "sim" else p.argv[3:]
            for p in layout.programs] == [p.argv for p in PROGS]
    assert "no batch scheduling: chrt (util-linux) is not installed" in layout.note


def test_without_the_cpu_latency_device_or_the_right_to_write_it_the_physics_is_placed_without_the_request(
        tmp_path, device, monkeypatch):
    missing = place(PROGS, "auto", {0, 1}, taskset=TASKSET, chrt=CHRT, latency_device=str(tmp_path / "none"))
    assert missing.physics_options == POLL and commands(missing) == [p.argv for p in PROGS]
    assert f"idle cores halting: no {tmp_path / 'none'} here" in missing.note
    # (This process may be root, who may write anything: the kernel's answer is stood in for.)
    monkeypatch.setattr("skillbus.cpu_layout.os.access", lambda path, mode: False)
    refused = place(PROGS, "auto", {0, 1}, taskset=TASKSET, chrt=CHRT, latency_device=device)
    assert refused.physics_options == POLL
    assert f"idle cores halting: {device} is not writable by this user (root's by default)" in refused.note


def test_nothing_is_asked_of_the_kernel_when_placement_is_off(device):
    assert place(PROGS, "off", {0, 1}, taskset=TASKSET, latency_device=device).physics_options == []
