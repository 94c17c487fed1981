"""The fault scenario of test_pick_and_place.py, run inside the test's sandbox: the system
under supervisord on the wall clock (as on a robot); ClearTable starts; during Pick the
skill process is killed; the task must fail naming it; supervisord must restart it; a
second ClearTable must finish the job. Prints one JSON line with what happened."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from skillbus import launch
from skillbus.skill import State
from skillbus.bus import channel, open_bus
from skillbus.demo import in_bin
from skillbus.msgs import decode, sim_state_t, skill_progress_t
from skillbus.system import programs
from skillbus.waiting import poll_until
from skillbus.world import WorldModelInterface

RUN = Path(sys.argv[1])
ARGS = ["-p", "Gripper=skiros:Gripper-7", "-p", "Arm=skiros:Arm-8", "-p", "Table=skiros:Table-1",
        "-p", "Bin=skiros:Bin-5"]
out = {}


def skill_run(*extra: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "skillbus.cli", "run", "ClearTable", *ARGS, *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def wait_registered(timeout: float = 60) -> bool:
    def listed() -> bool:
        r = subprocess.run([sys.executable, "-m", "skillbus.cli", "skills"], capture_output=True, text=True,
                           timeout=30)
        return "ClearTable" in r.stdout and "Pick" in r.stdout

    return bool(poll_until(listed, timeout, interval=0.5))


conf = launch.write_config(RUN, programs(RUN, task=None, lockstep=False), lockstep=False)
launch.start(conf, wait_s=60)
bus = open_bus()
state = {"pick": False, "sim": None}


def on_progress(ch, data):
    p = decode(skill_progress_t, data)
    if p is not None and any(n.type == "Pick" and n.state == State.Running for n in p.nodes):
        state["pick"] = True


def on_sim(ch, data):
    state["sim"] = data


bus.subscribe(channel("SB_SKILL_PROGRESS"), on_progress)
bus.subscribe(channel("SB_SIM_STATE"), on_sim)
try:
    out["registered"] = wait_registered()
    pid_before = int(launch.ctl(conf, "pid", "skills").stdout.strip())
    first = skill_run("-p", "Retries=0")  # no retry: the kill must fail the task
    poll_until(lambda: state["pick"], 60, step=bus.handle)
    out["pick_seen"] = state["pick"]
    os.kill(pid_before, signal.SIGKILL)
    killed_at = time.monotonic()
    text, _ = first.communicate(timeout=60)
    out["first_exit"] = first.returncode
    out["first_output"] = text[-3000:]
    out["failed_after_s"] = time.monotonic() - killed_at

    def skills_pid() -> int:
        try:
            return int(launch.ctl(conf, "pid", "skills").stdout.strip())
        except ValueError:
            return 0

    pid_after = poll_until(lambda: (p := skills_pid()) not in (0, pid_before) and p, 60, interval=0.2) or pid_before
    out["restarted"] = pid_after not in (0, pid_before)
    out["registered_again"] = wait_registered()
    second = skill_run()
    text, _ = second.communicate(timeout=240)
    out["second_exit"] = second.returncode
    out["second_output"] = text[-2000:]
    # Where the cubes are: the physics server's state and the world model.
    while bus.handle(0.0):  # what queued up while the runs went on is old: drop it
        pass
    state["sim"] = None
    poll_until(lambda: state["sim"] is not None, 10, interval=0.1, step=bus.handle)
    s = decode(sim_state_t, state["sim"])
    out["physics_in_bin"] = {o.name: in_bin(list(o.pose[:3])) for o in s.objects}
    out["physics"] = {o.name: list(o.pose[:3]) for o in s.objects}
    wmi = WorldModelInterface(bus, "fault-check")
    wmi.sync()
    out["world_model_bin"] = sorted(r["dst"] for r in wmi.get_relations("skiros:Bin-5", "skiros:contain", ""))
finally:
    launch.shutdown(conf)
print(json.dumps(out), flush=True)
