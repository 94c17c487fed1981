"""A number an option cannot mean is refused by argparse, naming the option (exit 2), before
anything opens a bus: before, `--timeout nan` ended in a traceback or meant "never",
`--timeout -1` was taken, `record --seconds -5` returned at once with an empty log (exit 0),
`--node-id 0` ended in canopen's TypeError, `lockstep-session --frames -5` never ended."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

CASES = [
    (["wm", "--timeout", "nan", "get", "x"], "--timeout"),
    (["sim", "--timeout", "-1", "status"], "--timeout"),
    (["map", "--timeout", "inf", "info"], "--timeout"),
    (["camera", "capture", "c", "--timeout", "nan"], "--timeout"),
    (["run", "Pick", "--timeout", "nan"], "--timeout"),
    (["watch", "1", "--timeout", "-1"], "--timeout"),
    (["record", "x.lcmlog", "--seconds", "-5"], "--seconds"),
    (["can-record", "--channel", "c", "x.log", "--seconds", "nan"], "--seconds"),
    (["replay", "x.lcmlog", "--speed", "0"], "--speed"),
    (["can-log", "x.log", "--node-id", "0"], "--node-id"),
    (["gripper-device", "--node-id", "200"], "--node-id"),
    (["gripper-device", "--period-ms", "nan"], "--period-ms"),
    (["lockstep-session", "--frames", "-5"], "--frames"),
    (["lockstep-session", "--python", "-2"], "--python"),
    (["skills-process", "--name", "x", "--register-timeout", "nan"], "--register-timeout"),
    (["plan", "--time-limit", "nan", "x"], "--time-limit"),
]


@pytest.mark.parametrize("args, option", CASES, ids=[" ".join(a[:1] + [o]) for a, o in CASES])
def test_a_number_an_option_cannot_mean_is_refused_naming_it(tmp_path, args, option):
    env = {**os.environ, "SKILLBUS_BUS_URL": "nowhere://this-bus-must-not-be-opened", "SKILLBUS_NETNS": "1"}
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", *args], capture_output=True, text=True, timeout=60,
                       env=env, cwd=tmp_path)
    assert p.returncode == 2, (p.returncode, p.stdout, p.stderr[-2000:])
    assert f"argument {option}" in p.stderr and "Traceback" not in p.stderr, p.stderr[-2000:]


@pytest.mark.parametrize("args, why", [(["replay", "LOG", "--channels", "["], "replay --channels '[': not a regular expression"),
                                       (["map", "clear", "everything"], "map clear takes no arguments"),
                                       (["map", "info", "foo"], "map info takes no arguments")],
                         ids=["replay-regex", "map-clear", "map-info"])
def test_what_a_command_would_misread_is_refused_naming_it(tmp_path, args, why):
    # Before: replay played nothing for the log's length and exited 0 (lcm-logplayer took
    # the expression it could not compile as matching nothing); `map clear everything`
    # cleared the whole map.
    log = tmp_path / "x.lcmlog"
    log.write_bytes(b"")
    env = {**os.environ, "SKILLBUS_BUS_URL": "nowhere://this-bus-must-not-be-opened", "SKILLBUS_NETNS": "1"}
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", *[str(log) if a == "LOG" else a for a in args]],
                       capture_output=True, text=True, timeout=60, env=env, cwd=tmp_path)
    assert p.returncode == 2 and why in p.stderr and "Traceback" not in p.stderr, (p.returncode, p.stderr[-2000:])


def test_a_skill_process_whose_libraries_all_fail_to_load_ends_naming_them(tmp_path):
    # Before, it went on serving no skill (RUNNING under supervisord; `run` then said only
    # "unknown skill").
    env = {**os.environ, "SKILLBUS_BUS_URL": "memq://", "SKILLBUS_NETNS": "1"}
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "x", "--library",
                        "no.such.module", "--standalone"], capture_output=True, text=True, timeout=60, env=env,
                       cwd=tmp_path)
    assert p.returncode == 2, (p.returncode, p.stderr[-2000:])
    assert "error: skills-process x: no skill loaded:" in p.stderr and "no.such.module" in p.stderr, p.stderr


@pytest.mark.parametrize("args, why", [(["--port", "70000"], "argument --port"), (["--port", "-1"], "argument --port"),
                                       (["--host", ""], "console --host: empty"),
                                       (["--token", "x", "--no-token"], "--token and --no-token: one or the other")],
                         ids=["port-high", "port-negative", "host-empty", "token-and-no-token"])
def test_the_consoles_address_and_token_are_what_was_asked_or_refused(tmp_path, args, why):
    # Before: --port 70000 a traceback; --host "" served every network; --token X --no-token
    # served without a token.
    env = {**os.environ, "SKILLBUS_BUS_URL": "nowhere://this-bus-must-not-be-opened", "SKILLBUS_NETNS": "1"}
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", "console", *args], capture_output=True, text=True,
                       timeout=60, env=env, cwd=tmp_path)
    assert p.returncode == 2 and why in p.stderr and "Traceback" not in p.stderr, (p.returncode, p.stderr[-2000:])


def test_a_tasks_tree_with_no_manager_says_so_and_refuses_parameters(tmp_path):
    # Before: "the skill manager does not know task 5" when no manager answered at all, and
    # `tree 5 -p K=V` ignored -p.
    env = {**os.environ, "SKILLBUS_BUS_URL": "memq://", "SKILLBUS_NETNS": "1"}
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", "tree", "5"], capture_output=True, text=True, timeout=60,
                       env=env, cwd=tmp_path)
    assert p.returncode == 1 and "no skill manager answered" in p.stderr, (p.returncode, p.stderr[-2000:])
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", "tree", "5", "-p", "K=V"], capture_output=True, text=True,
                       timeout=60, env=env, cwd=tmp_path)
    assert p.returncode == 2 and "-p is for a skill's expansion" in p.stderr, (p.returncode, p.stderr[-2000:])


@pytest.mark.parametrize("args, why", [(["--log-level", "bogus", "skills"], "argument --log-level: invalid choice"),
                                       (["launch", "--task", "Pick", "--no-task"], "not allowed with argument"),
                                       (["launch", "--task", ""], "argument --task: empty")],
                         ids=["log-level", "task-and-no-task", "task-empty"])
def test_options_that_were_dropped_without_a_word_are_refused(tmp_path, args, why):
    # Before: --log-level bogus became info; launch --task X --no-task dropped X; --task ""
    # started no task.
    env = {**os.environ, "SKILLBUS_BUS_URL": "nowhere://this-bus-must-not-be-opened", "SKILLBUS_NETNS": "1"}
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", *args], capture_output=True, text=True, timeout=60,
                       env=env, cwd=tmp_path)
    assert p.returncode == 2 and why in p.stderr and "Traceback" not in p.stderr, (p.returncode, p.stderr[-2000:])


@pytest.mark.parametrize("args, why", [(["--frames", "5"], "--frames needs --wall-clock"),
                                       (["--listen"], "--listen needs --bare")], ids=["frames", "listen"])
def test_a_demo_participant_refuses_what_its_mode_would_ignore(tmp_path, args, why):
    env = {**os.environ, "SKILLBUS_BUS_URL": "nowhere://this-bus-must-not-be-opened", "SKILLBUS_NETNS": "1"}
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", "lockstep-participant", "--name", "p", *args],
                       capture_output=True, text=True, timeout=60, env=env, cwd=tmp_path)
    assert p.returncode == 2 and why in p.stderr and "Traceback" not in p.stderr, (p.returncode, p.stderr[-2000:])


def test_can_log_names_a_log_or_an_eds_it_cannot_read(tmp_path):
    # Before: a .blf that is not BLF ended in struct.error's traceback, and an EDS that
    # could not be read was named as the log.
    env = {**os.environ, "SKILLBUS_NETNS": "1"}
    blf = tmp_path / "x.blf"
    blf.write_bytes(b"not a blf")
    log = tmp_path / "ok.log"
    log.write_text("(1.0) vcan0 705#05\n")
    for args, why in (([str(blf)], f"error: {blf}: not a readable CAN log"),
                      ([str(log), "--eds", str(tmp_path)], f"error: --eds {tmp_path}: not a readable EDS")):
        p = subprocess.run([sys.executable, "-m", "skillbus.cli", "can-log", *args], capture_output=True, text=True,
                           timeout=60, env=env)
        assert p.returncode == 2 and p.stderr.startswith(why) and "Traceback" not in p.stderr, (args, p.stderr[-2000:])


def test_an_empty_key_path_and_turtle_with_json_are_refused(tmp_path):
    # Before: `key rotate --path "$EMPTY"` rotated the default key file; `scene turtle --json`
    # ignored --json.
    home = tmp_path / "home"
    env = {**os.environ, "SKILLBUS_NETNS": "1", "XDG_CONFIG_HOME": str(home)}
    env.pop("SKILLBUS_KEY_FILE", None)
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", "key", "create", "--path", ""], capture_output=True,
                       text=True, timeout=60, env=env)
    assert p.returncode == 2 and "key --path: empty" in p.stderr, p.stderr
    assert not (home / "skillbus" / "bus.key").exists()  # the default key file, untouched
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", "scene", "turtle", "deploy/scenes/demo.scene.json",
                        "--json"], capture_output=True, text=True, timeout=60, env=env,
                       cwd=os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
    assert p.returncode == 2 and "--json is for check" in p.stderr, p.stderr


def test_a_skill_process_under_a_policy_without_the_expansion_rules_serves_on_without_them(tmp_path):
    # A policy file older than SB_SKTREE_* (skillbus tree's expansions): the process starts
    # and serves its skills, says once that it serves no expansions to operators, and never
    # answers where every answer would be refused (each was a failure in its log).
    from skillbus import auth
    key = tmp_path / "bus.key"
    auth.create_key_file(key)
    policy = tmp_path / "old.conf"
    policy.write_text("SB_SKPROC_*_REP skills\nSB_SKILL_HEARTBEAT skills\nSB_*_REQ *\n")
    env = {**os.environ, "SKILLBUS_BUS_URL": "memq://", "SKILLBUS_NETNS": "1", "SKILLBUS_KEY_FILE": str(key),
           "SKILLBUS_POLICY_FILE": str(policy), "SKILLBUS_IDENTITY": "skills",
           "PYTHONPATH": os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "integration",
                                      "skill_libs")}
    p = subprocess.Popen([sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "skills", "--library",
                          "flow_skills", "--standalone"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         env=env)
    try:
        first = p.stdout.readline()
        assert '"chain"' in first, first + p.stderr.read()
    finally:
        p.terminate()
        _, err = p.communicate(timeout=30)
    assert "expansions for operators (skillbus tree) not served: the bus policy" in err and "SB_SKTREE_SKILLS_REP" in err, err


@pytest.mark.parametrize("value, warned", [("bogus", True), ("Debug", False), ("warning", False)])
def test_a_log_level_from_the_environment_that_is_none_is_said(tmp_path, value, warned):
    # Before, a typo in $SKILLBUS_LOG_LEVEL logged at info without a word, in the C++
    # programs also "DEBUG" and "warning" (lower case only, "warn" only).
    from skillbus import paths
    env = {**os.environ, "SKILLBUS_BUS_URL": "nowhere://this-bus-must-not-be-opened", "SKILLBUS_NETNS": "1",
           "SKILLBUS_LOG_LEVEL": value}
    warning = f"warning: $SKILLBUS_LOG_LEVEL '{value}' is not debug, info, warn or error: logging at info"
    for argv in ([sys.executable, "-m", "skillbus.cli", "map", "info", "foo"], [str(paths.binary("wm_server")), "--help"]):
        p = subprocess.run(argv, capture_output=True, text=True, timeout=60, env=env, cwd=tmp_path)
        assert (warning in p.stderr) == warned, (argv, p.stderr[-2000:])
