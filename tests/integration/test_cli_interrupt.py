"""`skillbus run` interrupted (SIGINT, SIGTERM) or timed out preempts its task; with
--detach it leaves it running for `skillbus stop`; a command without a manager says so in
one line. Real processes: the C++ skill manager on the wall clock, a Python skill process
with flow_skills (Wait runs for Ticks ticks at 25 Hz), the CLI."""

import re
import signal
import sys
import time

from skillbus.waiting import wait_until
from test_skills import LIBS, cli, mgr_binary, start_system


def ready_system(sandbox):
    """The manager and a skill process, past the manager's start (on the wall clock its
    first frame waits up to 2 s for a world model; tasks queue meanwhile): task 1 has
    run, the task under test is task 2."""
    mgr, _ = start_system(sandbox, "flow_skills")
    rc, out, err = cli(sandbox, "run", "Wait", "-p", "Ticks=1", "--timeout", "30")
    assert rc == 0 and "task 1: Success" in out, out + err
    return mgr


def start_wait_run(sandbox, *extra):
    run = sandbox.start(f"run-{len(sandbox.procs)}",
                        [sys.executable, "-m", "skillbus.cli", "run", "Wait", "-p", "Ticks=1000", *extra],
                        env={"PYTHONPATH": str(LIBS)})
    return run


def wait_running(sandbox, run):
    """Until the task has been ticked a few times (watch the manager's log: ticks are
    only shown with --watch)."""
    wait_until(lambda: re.search(r"task 2: Wait \(wait\) started", sandbox.procs[0].stderr()), 20, "task 2 running",
               diagnostic=lambda: run.stdout() + run.stderr() + sandbox.procs[0].stderr()[-2000:])
    time.sleep(0.5)
    assert run.returncode is None, run.stdout() + run.stderr()


def assert_preempted(sandbox, mgr, run, code):
    rc = sandbox.wait(run, 15)
    out, err = run.stdout(), run.stderr()
    assert rc == code, f"exit {rc}\n{out}\n{err}"
    assert "Traceback" not in err and "lost sys.stderr" not in err, err
    assert "OSError" not in err and "BusError" not in err, err
    # The manager ended the task (preempted), and the client showed its end.
    assert re.search(r"task 2: Wait Failure: preempted at tick \d+", mgr.stderr()), mgr.stderr()[-2000:]
    assert re.search(r"task 2: Failure: preempted at tick \d+", out), out + err
    rc, _, err = cli(sandbox, "stop", "2")
    assert rc == 1 and "no running or queued task 2" in err, err


def test_sigint_preempts_the_task(sandbox):
    mgr = ready_system(sandbox)
    run = start_wait_run(sandbox, "--watch")
    wait_running(sandbox, run)
    sandbox.kill(run, signal.SIGINT)
    assert_preempted(sandbox, mgr, run, 130)


def test_sigterm_preempts_the_task(sandbox):
    mgr = ready_system(sandbox)
    run = start_wait_run(sandbox)
    wait_running(sandbox, run)
    sandbox.kill(run, signal.SIGTERM)
    assert_preempted(sandbox, mgr, run, 143)


def test_timeout_preempts_the_task(sandbox):
    mgr = ready_system(sandbox)
    run = start_wait_run(sandbox, "--timeout", "1")
    assert_preempted(sandbox, mgr, run, 3)
    assert "did not end within 1.0 s" in run.stderr()


def test_detach_leaves_the_task_running_for_stop(sandbox):
    mgr = ready_system(sandbox)
    t0 = time.monotonic()
    rc, out, err = cli(sandbox, "run", "Wait", "-p", "Ticks=1000", "--detach", timeout=20)
    assert rc == 0, out + err
    assert out.strip().splitlines()[-1] == "2", out  # the task id, alone on the last line
    assert time.monotonic() - t0 < 10
    time.sleep(1.0)  # the client is gone; the task runs on
    assert "task 2: Wait Failure" not in mgr.stderr(), mgr.stderr()[-2000:]
    rc, out, err = cli(sandbox, "pause", "2")
    assert rc == 0 and "paused" in out, out + err
    rc, out, err = cli(sandbox, "stop", "2")
    assert rc == 0 and "stopping" in out, out + err
    mgr.wait_for(re.compile(r"task 2: Wait Failure: preempted at tick \d+"), 10, what="the preempted task")


def test_no_manager_is_one_line(sandbox):
    for args in (("skills",), ("run", "Wait"), ("stop", "1")):
        t0 = time.monotonic()
        rc, out, err = cli(sandbox, *args, timeout=20)
        assert rc != 0, out + err
        assert "Traceback" not in err, err
        lines = err.strip().splitlines()
        assert len(lines) == 1, err
        assert lines[0].startswith("error: no skill manager answered on SB_SKILL_REQ within"), err
        assert "is the system running, in this network namespace?" in lines[0]
        assert time.monotonic() - t0 < 10


def test_a_manager_killed_under_a_run_is_named_at_once(sandbox):
    """kill -9 of the manager while `skillbus run` waits for its task: the run ends within
    seconds, naming the silent manager, instead of waiting out its --timeout."""
    mgr = ready_system(sandbox)
    run = start_wait_run(sandbox, "--timeout", "120")
    wait_running(sandbox, run)
    sandbox.kill(mgr, signal.SIGKILL)
    killed = time.monotonic()
    rc = sandbox.wait(run, 20)
    out, err = run.stdout(), run.stderr()
    assert rc == 1, f"exit {rc}\n{out}\n{err}"
    assert time.monotonic() - killed < 15.0  # (3.5 s of silence, a loaded machine's delays; not the 120 s)
    assert "task 2: Failure: the skill manager went silent: no announcement on SB_SKILL_MANAGER" in out, out + err
    assert "Traceback" not in err, err


def test_a_manager_restarted_under_a_run_is_named(sandbox):
    """The manager killed and started again at once (as supervisord does): the new
    incarnation's announcement tells the run its task was lost."""
    mgr = ready_system(sandbox)
    run = start_wait_run(sandbox, "--timeout", "120")
    wait_running(sandbox, run)
    sandbox.kill(mgr, signal.SIGKILL)
    sandbox.start("skill_mgr-2", [mgr_binary(), "--wall-clock"])
    rc = sandbox.wait(run, 20)
    out, err = run.stdout(), run.stderr()
    assert rc == 1, f"exit {rc}\n{out}\n{err}"
    assert re.search(r"task 2: Failure: (the skill manager restarted while task 2 ran \(incarnation -?\d+ -> -?\d+\)"
                     r"|the skill manager went silent)", out), out + err
