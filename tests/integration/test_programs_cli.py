"""The C++ programs' command lines (skillbus_apps on CLI11): --help lists every option
with a description and exits 0 without opening the bus; a wrong option or value ends the
program with exit code 2 and one line on stderr naming it. No network namespace needed:
nothing here opens the bus (SKILLBUS_BUS_URL points nowhere to make sure)."""

from __future__ import annotations

import os
import re
import subprocess

import pytest

from skillbus import paths

# Every program and the options scripts and tests use (their names must not change).
PROGRAMS = {
    "wm_server": ["--url", "--data", "--ontology", "--scene", "--name", "--wall-clock", "--period-ms",
                  "--snapshot-every", "--crash-after-commits", "--repair"],
    "skill_mgr": ["--url", "--name", "--wall-clock", "--period-ms", "--tick-hz", "--tick-timeout-ms", "--ontology",
                  "--start", "--robot", "--end-session-after-task", "--liveness-ms"],
    "sim_server": ["--url", "--scene", "--script", "--record-script", "--name", "--participants", "--wall-clock",
                   "--speed", "--frames", "--duration-s", "--pipeline", "--collision",
                   "--step-ms", "--frame-ms", "--join-timeout-ms", "--ack-timeout-ms", "--message-timeout-ms"],
    "motion_server": ["--url", "--scene"],
    "sb_scene": [],  # its subcommands check and turtle (their options: tests/py/test_scene_file.py)
    "sb_clock": ["--url", "--name", "--participants", "--frames", "--period-ms", "--join-timeout-ms",
                 "--ack-timeout-ms", "--message-timeout-ms", "--lose-clocks-every", "--demo"],
    "sb_demo_participant": ["--url", "--name", "--wall-clock", "--frames", "--clock-timeout-ms",
                            "--message-timeout-ms", "--drop-at-frame", "--slow-at-frame", "--bare"],
    "sb_rpc_counter": ["--url", "--area", "--drop-every", "--exit-after-idle-ms"],
}

# A numeric option of each program and a value it must refuse.
BAD_VALUES = {
    "wm_server": ("--snapshot-every", "often"),
    "skill_mgr": ("--tick-hz", "0"),
    "sim_server": ("--frames", "12x"),
    "sb_clock": ("--period-ms", "-1"),
    "sb_demo_participant": ("--drop-at-frame", "1.5"),
    "sb_rpc_counter": ("--drop-every", "some"),
}


def run(name: str, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, SKILLBUS_BUS_URL="nowhere://this-bus-must-not-be-opened")
    return subprocess.run([str(paths.binary(name)), *args], capture_output=True, text=True, timeout=30, env=env)


@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_help_lists_every_option_and_opens_no_bus(name):
    r = run(name, "--help")
    assert r.returncode == 0, r.stderr
    assert f"Usage: {name} [OPTIONS]" in r.stdout
    listed = dict(re.findall(r"^\s+(--[a-z-]+)\S*\s+(.*)$", r.stdout, re.M))
    for option in PROGRAMS[name]:
        assert option in listed, f"{name} --help does not list {option}:\n{r.stdout}"
        assert listed[option].strip(), f"{name} --help has no description for {option}"
    assert r.stderr == ""


@pytest.mark.parametrize("name", sorted(PROGRAMS))
def test_an_unknown_option_is_named_in_one_line(name):
    r = run(name, "--no-such-option", "1")
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert r.stdout == ""
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith(f"{name}: error: ") and "--no-such-option" in lines[0], lines[0]


@pytest.mark.parametrize("name", sorted(BAD_VALUES))
def test_a_wrong_value_is_named_in_one_line(name):
    option, value = BAD_VALUES[name]
    r = run(name, option, value)
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    lines = r.stderr.splitlines()
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith(f"{name}: error: ") and option in lines[0], lines[0]


@pytest.mark.parametrize("name", ["sim_server", "motion_server", "sb_demo_participant"])
def test_a_missing_required_option_is_named(name):
    required = "--name" if name == "sb_demo_participant" else "--scene"
    r = run(name)
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert r.stderr.startswith(f"{name}: error: {required}") and len(r.stderr.splitlines()) == 1, r.stderr


def test_a_bus_that_cannot_be_opened_is_one_line_too():
    r = run("sb_rpc_counter")  # parses, then opens the bus of SKILLBUS_BUS_URL
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert r.stderr.startswith("sb_rpc_counter: cannot start: bus URL 'nowhere://") and len(r.stderr.splitlines()) == 1


@pytest.mark.parametrize("name, extra", [("sim_server", ["--scene", "x.scene.json"]), ("sb_clock", [])])
@pytest.mark.parametrize("item", ["map", "map=", "=100", "map=0", "map=-5", "map=1.5", "map=10x"])
def test_a_malformed_per_participant_ack_timeout_is_named(name, extra, item):
    r = run(name, *extra, "--participants", "map", "--ack-timeout-ms-of", item)
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert r.stderr == f"{name}: error: --ack-timeout-ms-of {item}: expected NAME=MS with MS a positive whole " \
                       "number (see --help)\n", r.stderr


def test_an_ack_timeout_for_someone_who_is_no_participant_is_named():
    r = run("sb_clock", "--participants", "a,b", "--ack-timeout-ms-of", "c=100")
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert r.stderr == "sb_clock: error: --ack-timeout-ms-of names 'c', who is not among --participants (see --help)\n"


def test_the_world_models_change_hold_is_for_the_wall_clock_only():
    # (under lockstep changes go out in frames, for everyone alike: a hold would be ignored)
    r = run("wm_server", "--hold-changes-ms", "300")
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert r.stderr.startswith("wm_server: error: --hold-changes-ms requires --wall-clock"), r.stderr
    assert len(r.stderr.splitlines()) == 1, r.stderr
    r = run("wm_server", "--hold-changes-ms", "-1", "--wall-clock")
    assert r.returncode == 2 and "--hold-changes-ms" in r.stderr, r.stderr


# An option of the other clock mode was ignored without a word (a user's --speed under
# lockstep, --participants on the wall clock): each is refused, naming it.
OTHER_MODE = [
    ("sim_server", ["--scene", "x.scene.json", "--wall-clock", "--participants", "a"], "--participants"),
    ("sim_server", ["--scene", "x.scene.json", "--wall-clock", "--pipeline"], "--pipeline"),
    ("sim_server", ["--scene", "x.scene.json", "--wall-clock", "--join-timeout-ms", "100"], "--join-timeout-ms"),
    ("sim_server", ["--scene", "x.scene.json", "--wall-clock", "--ack-timeout-ms", "100"], "--ack-timeout-ms"),
    ("sim_server", ["--scene", "x.scene.json", "--wall-clock", "--ack-poll-us", "100"], "--ack-poll-us"),
    ("sim_server", ["--scene", "x.scene.json", "--speed", "2"], "--speed"),
    ("skill_mgr", ["--liveness-ms", "100"], "--liveness-ms"),
    ("skill_mgr", ["--period-ms", "20"], "--period-ms"),
    ("wm_server", ["--period-ms", "20"], "--period-ms"),
]


@pytest.mark.parametrize("name, args, option", OTHER_MODE, ids=[f"{n}{o}" for n, a, o in OTHER_MODE])
def test_an_option_of_the_other_clock_mode_is_refused_naming_it(name, args, option):
    r = run(name, *args)
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert r.stderr.startswith(f"{name}: error: {option} is for ") and len(r.stderr.splitlines()) == 1, r.stderr
