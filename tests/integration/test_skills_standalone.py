"""skills-process --standalone serves ticks with no skill manager on the bus (what a program
that ticks the process itself, bench/tick_rtt_bench, needs): it does not register, does
not exit for want of a manager, and answers START and EXECUTE ticks."""

import json
import os
import subprocess
import sys
import textwrap

from skillbus import paths

TICKER = textwrap.dedent("""
    import json, time
    from skillbus.bus import open_bus
    from skillbus.msgs import skill_tick_t, skill_tick_reply_t
    from skillbus.rpc import RpcClient
    client = RpcClient(open_bus(), "SKPROC_ALONE", "ticker")
    states = []
    for action in (skill_tick_t.START, skill_tick_t.EXECUTE, skill_tick_t.EXECUTE):
        t = skill_tick_t(); t.label, t.instance, t.action, t.frame = "spin", 1, action, -1
        states.append(client.call("tick", t, skill_tick_reply_t, timeout=10).message)
    print(json.dumps(states))
""")


def test_a_standalone_skill_process_answers_ticks_without_a_manager(sandbox):
    bench = paths.REPO_ROOT / "bench"
    proc = sandbox.start("alone", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "alone",
                                   "--library", "spin_skills", "--standalone", "--register-timeout", "1"],
                         env={"PYTHONPATH": str(bench)})
    proc.wait_for("without a skill manager", 60)
    t = sandbox.start("ticker", [sys.executable, "-c", TICKER])
    assert sandbox.wait(t, 60) == 0, t.stderr()
    assert json.loads(t.stdout().strip().splitlines()[-1]) == ["spinning", "spinning", "spinning"]
    assert proc.returncode is None  # still serving, past its --register-timeout


def test_standalone_under_lockstep_is_refused_naming_why():
    r = subprocess.run([sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "x", "--library",
                        "spin_skills", "--standalone", "--lockstep"], capture_output=True, text=True, timeout=60,
                       env={**os.environ, "PYTHONPATH": str(paths.REPO_ROOT / "bench")})
    assert r.returncode == 2 and "not with --lockstep" in r.stderr, r.stderr
