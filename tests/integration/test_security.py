"""The security suite: the system on the wall clock under supervisord, with its key and
policy, probed while ClearTable runs by outsiders without the key, with a wrong key, by
replays of genuine messages, by a key holder on another program's channels, and from a
second host (a network namespace over a veth pair). Nothing is applied, every refusal is
counted by the receivers, and the task succeeds (security_probe.py does the work)."""

import json

from conftest import lcm_only, python_tool


def test_outsiders_replays_and_other_hosts_command_nothing(sandbox, tmp_path):
    run = tmp_path / "sec"
    run.mkdir()
    proc = sandbox.start("probe", python_tool("security_probe.py", "system", str(run)))
    assert sandbox.wait(proc, 400) == 0, proc.stdout()[-3000:] + proc.stderr()[-3000:]
    r = json.loads(proc.stdout().strip().splitlines()[-1])
    where = json.dumps(r)[:4000]
    # Every request went unanswered (dropped before any server looked at it).
    for who in ("no_key", "wrong_key"):
        for call in ("wm_commit", "wm_load_scene", "sim_pause"):
            assert r[who][call] == "no answer", where
    if sandbox.transport == "lcm":  # (udpm:// multicast reaches the veth; DDS stays on loopback)
        assert r["veth"].get("arrived") and all(r["veth"][c] == "no answer" for c in ("wm_commit", "sim_pause")), where
    # Nothing was applied: no forged element (not in the server, not in a replica's view
    # that followed a forged change), the world not wiped, the physics not paused, the arm
    # never took a probe's command.
    assert r["forged_elements"] == [] and r["elements"] >= 9, where
    assert r["sim_paused"] is False, where
    assert r["arm_commands_seen_by_sim"] == 0, where
    # The task ran through it all.
    assert r["task_exit"] == 0, r["task_output"]
    # Each refusal was counted where it arrived: unsigned (no key, the other host), forged
    # (a wrong key), replayed, forbidden (an operator's tool on the arm's channel).
    wm, sim = r["rejected"]["wm"], r["rejected"]["sim"]
    assert wm.get("unsigned", 0) >= 3 and wm.get("bad_mac", 0) >= 2 and wm.get("replayed", 0) >= 1, where
    assert sim.get("unsigned", 0) >= 2 and sim.get("bad_mac", 0) >= 2, where
    assert sim.get("replayed", 0) >= 1 and sim.get("forbidden", 0) >= 1, where
    assert r["rejected"]["skill_mgr"].get("replayed", 0) >= 0 and r["skills_log_dropped"] >= 1, where


def test_forged_clocks_neither_stop_a_lockstep_session_nor_take_it_over(sandbox, tmp_path):
    """Stop clocks sent before the session starts and all through it, without a key, with
    a wrong key, and with the key under the operator's identity (the policy gives the
    clock to the physics server only): the session runs ClearTable to its end."""
    run = tmp_path / "ls"
    run.mkdir()
    proc = sandbox.start("probe", python_tool("security_probe.py", "lockstep", str(run)))
    assert sandbox.wait(proc, 400) == 0, proc.stdout()[-3000:] + proc.stderr()[-3000:]
    r = json.loads(proc.stdout().strip().splitlines()[-1])
    where = json.dumps(r)[:3000]
    assert r["ended"] and r["sessions"] == 1 and r["forged_clocks_sent"] > 300, where
    assert r["sim"]["ok"] and r["sim"]["frames"] == 1669, where  # the demo's frames (the arm goes around the post)
    assert r["skill_mgr"]["ok"] and r["skill_mgr"]["tasks"] == {"1": "Success: all succeeded"}, where
    for who in ("skill_mgr", "wm"):
        got = r[who]["bus_rejected"]
        assert got.get("unsigned", 0) > 0 and got.get("bad_mac", 0) > 0 and got.get("forbidden", 0) > 0, where


@lcm_only("udpm:// joins a multicast group; DDS talks on its URL's interface (tests/py/test_dds_url.py)")
def test_the_bus_stays_on_this_host_unless_a_network_is_chosen(sandbox, tmp_path):
    """In a namespace whose multicast route leaves through a network interface (a dummy
    one here), every entry point refuses to join the group there, naming the interface and
    what to do; --network IFACE (or SKILLBUS_NETWORK) allows it. (A veth pair stands in
    for a network card: the kernel here has no dummy interfaces.)"""
    import sys
    from skillbus import paths
    setup = sandbox.start("net", ["sh", "-c", "ip link add d0 type veth peer name d1 && ip addr add 10.88.0.1/24 dev d0 && "
                                              "ip link set d1 up && ip link set d0 up multicast on && "
                                              "ip route replace 224.0.0.0/4 dev d0"])
    assert sandbox.wait(setup, 10) == 0, setup.stderr()
    wm = sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", tmp_path / "wm"])
    assert sandbox.wait(wm, 10) != 0
    assert "would be joined on the network interface d0," in wm.stderr(), wm.stderr()
    assert "--network d0" in wm.stderr()
    cli = sandbox.start("cli", [sys.executable, "-m", "skillbus.cli", "skills"])
    assert sandbox.wait(cli, 30) == 1 and "network interface d0" in cli.stderr(), cli.stderr()
    # Chosen: the C++ server starts (and is stopped), the CLI gets as far as asking for a manager.
    wm = sandbox.start("wm-net", [paths.binary("wm_server"), "--wall-clock", "--data", tmp_path / "wm2",
                                  "--network", "d0"])
    cli = sandbox.start("cli-net", [sys.executable, "-m", "skillbus.cli", "--network", "d0", "skills"])
    assert sandbox.wait(cli, 30) == 1 and "no skill manager answered" in cli.stderr(), cli.stderr()
    assert wm.returncode is None, wm.stderr()
