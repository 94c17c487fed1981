"""`skillbus launch` with a relative --run-dir from another directory works, and a launch
that fails shuts down what it started. supervisord daemonizes (it leaves the sandbox's
process group), so processes are found by the sandbox's network namespace, and whatever
a test leaves behind is killed by it."""

import os
import re
import signal
import sys
import time
from pathlib import Path

import pytest

from skillbus import paths
from skillbus.waiting import poll_until

LAUNCH = ["launch", "--wall-clock", "--no-task", "--run-dir", "rel/robot"]
PROGRAMS = {"can_hub", "sim", "motion", "wm", "gripper", "skill_mgr", "skills"}


def netns_procs(sandbox) -> dict[int, str]:
    """pid -> command line of every process in the sandbox's network namespace, but its
    holder and the processes the test started itself."""
    holder = sandbox._holder.pid
    ns = os.readlink(f"/proc/{holder}/ns/net")
    own = {p.popen.pid for p in sandbox.procs if p.popen.poll() is None}
    out = {}
    for d in os.listdir("/proc"):
        if not d.isdigit() or int(d) in (holder, *own):
            continue
        try:
            if os.readlink(f"/proc/{d}/ns/net") != ns:
                continue
            cmd = Path(f"/proc/{d}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace").strip()
        except OSError:
            continue  # gone meanwhile
        if cmd:  # (a zombie has no command line)
            out[int(d)] = cmd
    return out


def wait_no_procs(sandbox, timeout: float) -> dict[int, str]:
    left: dict[int, str] = {}

    def none_left() -> bool:
        left.clear()
        left.update(netns_procs(sandbox))
        return not left

    poll_until(none_left, timeout, interval=0.2)
    return left


@pytest.fixture
def box(sandbox):
    yield sandbox
    for pid in netns_procs(sandbox):  # whatever a failed test left behind
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def skillbus_in(box, cwd: Path, *args, timeout: float):
    """`skillbus ARGS` run from the directory cwd (in the sandbox)."""
    p = box.start(f"skillbus-{args[0]}-{len(box.procs)}",
                  ["sh", "-c", 'cd "$0" && exec "$@"', str(cwd), sys.executable, "-m", "skillbus.cli", *args])
    rc = box.wait(p, timeout)
    return rc, p.stdout(), p.stderr()


def test_relative_run_dir_from_another_directory(box, tmp_path):
    cwd = tmp_path / "elsewhere"
    cwd.mkdir()
    assert not (paths.REPO_ROOT / "rel").exists()
    rc, out, err = skillbus_in(box, cwd, *LAUNCH, timeout=120)
    assert rc == 0, out + err
    for name in PROGRAMS:
        assert re.search(rf"^  {name}\s+RUNNING$", out, re.M), out
    run = cwd / "rel" / "robot"
    assert (run / "wm").is_dir()  # the world model's data where the user asked for it
    assert not (paths.REPO_ROOT / "rel").exists()  # (not under the programs' directory)
    conf = (run / "supervisord.conf").read_text()
    for value in re.findall(r"^(?:file|logfile|pidfile|childlogdir|directory|serverurl|stdout_logfile|"
                            r"stderr_logfile)=(?:unix://)?(.*)$", conf, re.M):
        assert Path(value).is_absolute(), value
    for command in re.findall(r"^command=(.*)$", conf, re.M):
        for arg in command.split():
            assert "rel/robot" not in arg or arg.startswith(str(run)), command
    assert len(netns_procs(box)) == len(PROGRAMS) + 1  # supervisord and its programs
    rc, out, err = skillbus_in(box, cwd, "shutdown", "--run-dir", "rel/robot", timeout=60)
    assert rc == 0, out + err
    left = wait_no_procs(box, 20)
    assert not left, left


def test_a_failed_launch_leaves_nothing_behind(box, tmp_path):
    cwd = tmp_path / "elsewhere"
    (cwd / "rel" / "robot").mkdir(parents=True)
    (cwd / "rel" / "robot" / "wm").write_text("not a directory")  # the world model cannot start
    t0 = time.monotonic()
    rc, out, err = skillbus_in(box, cwd, *LAUNCH, timeout=120)
    assert rc != 0, out + err
    assert "Traceback" not in err, err
    assert re.search(r"\bwm\b.*FATAL", err), err  # names the program ...
    assert "wm_server: cannot start: cannot open" in err, err  # ... and shows the end of its log
    assert time.monotonic() - t0 < 60
    left = wait_no_procs(box, 20)
    assert not left, left
    assert not (cwd / "rel" / "robot" / "supervisord.pid").exists()
