"""The manager-restart scenario of test_manager_restart.py, run inside the test's sandbox:
the pick-and-place system under supervisord on the wall clock (as on a robot); kill -9 of
the skill manager; supervisord restarts it; the skill process registers again when the
new manager's announcement does not list it; then ClearTable must succeed. Prints one
JSON line with what happened."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from skillbus import launch
from skillbus.system import programs
from skillbus.waiting import poll_until

RUN = Path(sys.argv[1])
ARGS = ["-p", "Gripper=skiros:Gripper-7", "-p", "Arm=skiros:Arm-8", "-p", "Table=skiros:Table-1",
        "-p", "Bin=skiros:Bin-5"]
out: dict = {}


def skills() -> str:
    r = subprocess.run([sys.executable, "-m", "skillbus.cli", "skills"], capture_output=True, text=True, timeout=30)
    return r.stdout if r.returncode == 0 else ""


def wait_for(pred, timeout: float) -> bool:
    return bool(poll_until(pred, timeout, interval=0.1))


conf = launch.write_config(RUN, programs(RUN, task=None, lockstep=False), lockstep=False)
launch.start(conf, wait_s=60)
try:
    out["registered"] = wait_for(lambda: "ClearTable" in skills(), 60)
    listed = skills()
    pid_before = int(launch.ctl(conf, "pid", "skill_mgr").stdout.strip())
    os.kill(pid_before, signal.SIGKILL)
    killed_at = time.monotonic()

    def restarted() -> bool:
        try:
            pid = int(launch.ctl(conf, "pid", "skill_mgr").stdout.strip())
        except ValueError:
            return False
        return pid not in (0, pid_before)

    out["restarted"] = wait_for(restarted, 30)
    out["restarted_after_s"] = time.monotonic() - killed_at
    restarted_at = time.monotonic()
    out["listed_again"] = wait_for(lambda: skills() == listed, 30)
    out["listed_after_restart_s"] = time.monotonic() - restarted_at
    out["listed_after_kill_s"] = time.monotonic() - killed_at
    run = subprocess.run([sys.executable, "-m", "skillbus.cli", "run", "ClearTable", *ARGS, "--timeout", "240"],
                         capture_output=True, text=True, timeout=300)
    out["clear_exit"] = run.returncode
    out["clear_output"] = (run.stdout + run.stderr)[-2000:]
finally:
    launch.shutdown(conf)
print(json.dumps(out), flush=True)
