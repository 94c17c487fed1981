"""Two simulated hosts (skillbus.hosts: the sandbox's namespace and a child one joined by a
veth pair), over LCM with ttl=1 and over Cyclone DDS with each host's address and the
other as its peer. The world model, physics, motion service and skill manager run on
host A; the skill process, the gripper device and its CAN hub on host B. The digests
are those of one host; a cut cable is reported, naming who was cut off."""

from __future__ import annotations

import re

import pytest

from clear_table_run import run_clear_table
from conftest import TRANSPORTS, last_json
from skillbus.hosts import TwoHosts
from skillbus.lockstep_session import python_participant_argv
from skillbus.netns import Sandbox
from skillbus.paths import binary

ON_B = {"skills": "b", "gripper": "b", "can_hub": "b"}


@pytest.fixture(scope="module")
def one_host(tmp_path_factory) -> dict:
    run = tmp_path_factory.mktemp("one_host")
    with Sandbox(log_dir=run / "logs") as box:
        return run_clear_table(box, run)


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_the_system_split_over_two_hosts_gives_the_digests_of_one(tmp_path, transport, one_host):
    run = tmp_path / transport
    run.mkdir()
    with TwoHosts(log_dir=run / "logs", transport=transport, placement=ON_B) as box:
        two = run_clear_table(box, run)
        assert {n: box.started_on[n] for n in ON_B} == ON_B  # (they did run on B)
        assert box.started_on["sim"] == box.started_on["wm"] == box.started_on["skill_mgr"] == "a"
    assert two["skill_mgr"]["tasks"] == {"1": "Success: all succeeded"}, two["skill_mgr"]
    for key in ("frames", "state_digest", "session_digest"):
        assert two["sim"][key] == one_host["sim"][key], key
    for n in ("wm", "skill_mgr", "skills", "gripper"):
        assert two[n]["digest"] == one_host[n]["digest"], n
    assert two["world_model"] == one_host["world_model"]


@pytest.mark.parametrize("transport", TRANSPORTS)
def test_a_cut_cable_is_reported_naming_the_participant_cut_off(tmp_path, transport):
    with TwoHosts(log_dir=tmp_path / "logs", transport=transport, placement={"far": "b"}) as box:
        clock = box.start("clock", [binary("sb_clock"), "--demo", "--frames", "10000000",
                                    "--participants", "near,far", "--ack-timeout-ms", "1500"])
        # near's wait for far's messages must end before the master's wait for acks (as
        # with the defaults, 2 s and 5 s): else near, still waiting, is named as well.
        box.start("near", python_participant_argv("near", "--message-timeout", "0.5"))
        box.start("far", python_participant_argv("far", "--clock-timeout", "3", "--message-timeout", "0.5"))
        clock.wait_for("starting frames", 30)
        clock.wait_for(" joined", 5)
        box.cut()
        assert box.wait(clock, 30) == 1
        err = clock.stderr() + clock.stdout()
        error = last_json(clock.stdout())["error"]  # (the summary also counts each participant's frames)
        # far's ack missing, or near noticing far's message lost (the cut can fall between
        # far's ack, which the master got, and its message to near): either way far is named.
        named = re.search(r"participant\(s\) ([\w, ]+?)(?: within|:)", error)
        assert named and named.group(1) == "far", err[-2000:]
        assert "no ack" in error or "message lost" in error, err[-2000:]
