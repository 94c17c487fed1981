"""Quiet lockstep frames of Python participants acked by skillbus_native.QuietFrames
(skillbus.quiet_frames): a C++ clock master, Python and C++ participants, over LCM in a
private network namespace. Every session is run with the core and without it
(SKILLBUS_NATIVE=0: Python takes every clock, and verifies and signs every message);
both must give the same digests, the same messages heard, and the same refusals of
forged clocks."""

import pytest

from conftest import last_json, python_tool
from skillbus.lockstep_session import python_participant_argv
from skillbus.netns import Sandbox

WITHOUT_CORE = {"SKILLBUS_NATIVE": "0"}


def session(box, binary, frames, participants, clock_args=(), env=None, timeout=120):
    """Runs sb_clock --demo with `participants` ({name: extra argv}); names starting with
    "py" are Python participants. The master's summary and each participant's."""
    clock = box.start("clock", [binary("sb_clock"), "--demo", "--frames", str(frames),
                                "--participants", ",".join(participants), *clock_args])
    procs = {n: box.start(n, python_participant_argv(n, *extra) if n.startswith("py")
                          else [binary("sb_demo_participant"), "--name", n, *extra], env=env)
             for n, extra in participants.items()}
    box.wait(clock, timeout)
    results = {}
    for n, p in procs.items():
        box.wait(p, 30)
        results[n] = last_json(p.stdout())
    return last_json(clock.stdout()), results


def outcome(master, results):
    """What must not depend on who acked a frame: the digests and what each one heard."""
    return master["digest"], {n: (r["digest"], r["received"], r["state"] if "state" in r else None, r["frames"])
                              for n, r in results.items()}


# py_talk publishes in every 7th frame only: py_hear's frames are quiet but for those
# (it folds what it hears); py_bare has nothing to do in any frame.
MIXED = {"py_talk": ["--every", "7"], "py_hear": ["--bare", "--listen"], "py_bare": ["--bare"],
         "cpp_bare": ["--bare"]}


def test_quiet_frames_give_the_same_digests_and_messages_as_python(tmp_path, binary):
    frames = 1500
    runs = {}
    for label, env in (("python", WITHOUT_CORE), ("core", None)):
        with Sandbox(log_dir=tmp_path / label) as box:
            runs[label] = session(box, binary, frames, MIXED, env=env)
    for master, results in runs.values():
        assert master["ok"], master["error"]
        assert all(r["ok"] and r["frames"] == frames for r in results.values()), results
    assert outcome(*runs["core"]) == outcome(*runs["python"])
    py = runs["python"][1]
    core = runs["core"][1]
    assert all(py[n]["quiet_frames"] == 0 for n in ("py_talk", "py_hear", "py_bare"))
    # Frame 0 is Python's (the core starts once the master is known and a frame acked).
    assert core["py_bare"]["quiet_frames"] == frames - 1
    talked = len(range(0, frames - 1, 7))  # (what py_talk says in the last frame no clock announces)
    assert core["py_hear"]["received"] == talked
    assert core["py_hear"]["quiet_frames"] == frames - 1 - talked
    assert core["py_talk"]["quiet_frames"] == 0  # it has a frame callback: never quiet


def test_lost_clocks_and_a_slow_participant_give_the_same_digests_with_the_core(tmp_path, binary):
    # The master resends a clock that was lost (a new frame for everyone) and the clock
    # of a frame a slow participant still works on (the others answer with their ack).
    frames = 600
    parts = {"py_slow": ["--slow-at-frame", "300", "--slow-s", "1.2"], "py_hear": ["--bare", "--listen"],
             "py_bare": ["--bare"], "cpp_bare": ["--bare"]}
    clock_args = ["--lose-clocks-every", "97", "--ack-timeout-ms", "5000"]
    runs = {}
    for label, env in (("python", WITHOUT_CORE), ("core", None)):
        with Sandbox(log_dir=tmp_path / label) as box:
            runs[label] = session(box, binary, frames, parts, clock_args, env=env)
    for master, results in runs.values():
        assert master["ok"], master["error"]
        assert all(r["ok"] for r in results.values()), results
    assert outcome(*runs["core"]) == outcome(*runs["python"])
    assert runs["core"][1]["py_bare"]["quiet_frames"] > frames // 2


@pytest.mark.parametrize("attack,reason", [("unsigned", "unsigned"), ("wrong-key", "bad_mac"),
                                           ("replay", "replayed")])
def test_forged_and_replayed_clocks_are_refused_and_counted_by_the_core(tmp_path, binary, attack, reason):
    frames = 1500
    parts = {"py_a": ["--bare"], "py_b": ["--bare", "--listen"], "py_talk": ["--every", "5"], "cpp_bare": ["--bare"]}
    with Sandbox(log_dir=tmp_path / "clean") as box:
        clean = session(box, binary, frames, parts, env=WITHOUT_CORE)
    with Sandbox(log_dir=tmp_path / attack) as box:
        # A clock of the master's name listing everyone, for frames 1 to 3000 in turn:
        # acted on, it would start frames early and the digests would differ.
        forger = box.start("forger", python_tool("clock_forger.py", attack, "clock", ",".join(parts), "8"))
        attacked = session(box, binary, frames, parts)
        box.wait(forger, 30)
        assert last_json(forger.stdout())["sent"] > 0
    for master, results in (clean, attacked):
        assert master["ok"], master["error"]
        assert all(r["ok"] and r["frames"] == frames for r in results.values()), results
    assert outcome(*attacked) == outcome(*clean)
    for n in ("py_a", "py_b"):
        r = attacked[1][n]
        assert r["quiet_frames"] > frames // 2, r
        assert r["rejected"].get(reason, 0) > 0, r
        if attack != "unsigned":  # (an unsigned clock is Python's to drop: the core verifies what it acts on)
            assert r["core_rejected"].get(reason, 0) > 0, r


def test_latest_only_frames_are_acked_by_the_core_and_hand_python_the_newest_state(tmp_path, binary):
    # py_latest reads SB_DEMO_STATE (published by the master every frame) latest-only and
    # acts in every 10th frame: the nine frames between are the core's, which collects and
    # verifies each frame's state and hands Python the newest. What py_latest publishes
    # (and py_hear folds) must be what Python reading every state gives.
    frames = 1500
    parts = {"py_latest": ["--latest-every", "10"], "py_hear": ["--bare", "--listen"], "cpp_bare": ["--bare"]}
    runs = {}
    for label, env in (("python", WITHOUT_CORE), ("core", None)):
        with Sandbox(log_dir=tmp_path / label) as box:
            runs[label] = session(box, binary, frames, parts, env=env)
    for master, results in runs.values():
        assert master["ok"], master["error"]
        assert all(r["ok"] and r["frames"] == frames for r in results.values()), results
    assert outcome(*runs["core"]) == outcome(*runs["python"])
    latest = runs["core"][1]["py_latest"]
    assert runs["python"][1]["py_latest"]["quiet_frames"] == 0
    assert latest["received"] == len(range(0, frames, 10))
    # Frames 0 and 1 are Python's (no master known, then no frame acked); after that each
    # tenth frame is Python's and the nine between the core's.
    assert frames * 9 // 10 - 10 <= latest["quiet_frames"] <= frames * 9 // 10, latest
    assert latest["bad_input"] == 0
