"""One trial of the fault suite (test_fault_suite.py), run inside the test's sandbox:

    fault_trial.py RUN_DIR PROCESS CLOCK SEED

The pick-and-place system under supervisord (CLOCK: "lockstep" or "wall"); ClearTable
starts; at a moment drawn from SEED (a frame under lockstep, a time on the wall clock)
PROCESS gets SIGKILL. Then it records how the fault showed (the failed task's or the
ended session's message, and how long after the kill), waits for the system to come
back, runs the next ClearTable, and compares the world model with the physics. Prints
one JSON line; the test judges it.

Under lockstep the task is the skill manager's --start task: a session that a fault ends
(a participant or the clock master died) ends every process with an error, supervisord
restarts them, and the new session runs ClearTable again: that run is "the next
ClearTable". When the session survives the fault (the motion service or the CAN hub
died: they are servers, not participants), the task's end ends the session and the trial
starts the next one itself.
"""

from __future__ import annotations

import json
import os
import random
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from skillbus import launch
from skillbus.bus import channel, open_bus
from skillbus.demo import in_bin, world_model_after
from skillbus.msgs import decode, sim_state_t
from skillbus.system import TASK, programs
from skillbus.waiting import poll_until
from skillbus.world import WorldModelInterface
from skillbus.world.poses import world_pose

RUN, PROCESS, CLOCK, SEED = Path(sys.argv[1]), sys.argv[2], sys.argv[3], int(sys.argv[4])
LOCKSTEP = CLOCK == "lockstep"
ARGS = [a for kv in TASK.split()[1:] for a in ("-p", kv)]
PRODUCTS = {"red": "skiros:Cube-2", "green": "skiros:Cube-3", "blue": "skiros:Cube-4"}
rng = random.Random(SEED)
out: dict = {"process": PROCESS, "clock": CLOCK, "seed": SEED}


def log(msg: str) -> None:
    print(f"[{time.monotonic():.1f}] {msg}", file=sys.stderr, flush=True)


def json_lines(path: Path) -> list[dict]:
    """The end-of-run JSON summaries a program printed, one per run of it (supervisord
    appends); a skill process's registration line is not one."""
    lines = []
    try:
        text = path.read_text(errors="replace")
    except OSError:
        return lines
    for line in text.splitlines():
        if line.startswith("{"):
            try:
                summary = json.loads(line)
            except ValueError:
                continue
            if "ok" in summary:
                lines.append(summary)
    return lines


def pid_of(name: str) -> int:
    return launch.program_pids(conf).get(name, 0)


def compare(wm: dict[str, list[float]], physics: dict[str, list[float]]) -> dict[str, float]:
    """Per product: the distance between the world model's pose and the physics', m."""
    return {n: round(sum((a - b) ** 2 for a, b in zip(wm[n], physics[n])) ** 0.5, 4) if n in wm and n in physics
            else -1.0 for n in PRODUCTS}


def skill_run(timeout: float) -> tuple[int, str]:
    r = subprocess.run([sys.executable, "-m", "skillbus.cli", "run", "ClearTable", *ARGS, "--timeout", str(timeout)],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=timeout + 30)
    return r.returncode, r.stdout


def registered() -> bool:
    r = subprocess.run([sys.executable, "-m", "skillbus.cli", "skills"], capture_output=True, text=True, timeout=30)
    return "ClearTable" in r.stdout and "TransferProducts" in r.stdout


conf = launch.write_config(RUN, programs(RUN, task=TASK if LOCKSTEP else None, lockstep=LOCKSTEP), lockstep=LOCKSTEP)
logs = RUN / "logs"
bus = open_bus()
seen = {"frame": -1, "sim": None}


def on_sim(ch, data):
    s = decode(sim_state_t, data)
    if s is not None:
        seen["frame"] = s.header.frame
        seen["sim"] = s


bus.subscribe(channel("SB_SIM_STATE"), on_sim)
# The frames are read from before the system starts, in a thread, until the kill: a
# lockstep session runs at 5x real time, and frames read only after launch.start returned
# were a backlog: on a loaded machine the session had ended before the trial saw its kill
# frame, and the trial then killed "pid 0", its own process group (no output at all).
reading = threading.Event()
reading.set()


def read_frames() -> None:
    while reading.is_set():
        bus.handle(0.05)


def stop_reading() -> None:
    reading.clear()
    reader.join(5)


reader = threading.Thread(target=read_frames, daemon=True)
reader.start()
launch.start(conf, wait_s=90)
try:
    if not LOCKSTEP:
        stop_reading()  # (the main thread reads the bus from here on)
    if LOCKSTEP:
        # A frame of the first session's 1,615 (ClearTable at 20 ms frames).
        kill_frame = rng.randrange(20, 1550)
        out["kill_frame"] = kill_frame
        reached = poll_until(lambda: seen["frame"] >= kill_frame, 120)
        out["kill_reached"] = bool(reached)
        victim = pid_of(PROCESS)
        stop_reading()
        if victim <= 0:  # (os.kill(0) would kill this trial's own process group)
            raise SystemExit(f"{PROCESS} is not running at the kill frame {kill_frame} (frame seen: {seen['frame']})")
        os.kill(victim, signal.SIGKILL)
        killed_at = time.monotonic()
        log(f"killed {PROCESS} (pid {victim}) at frame {seen['frame']}")
        # The first session's end: the task's result (the session went on) or the error
        # that ended it, whichever a program reports first.
        first = {}

        def first_end() -> bool:
            for name in ("sim", "skill_mgr", "wm", "skills", "gripper"):
                runs = json_lines(logs / f"{name}.out")
                if runs:
                    first.update(program=name, summary=runs[0])
                    return True
            return False

        poll_until(first_end, 60, interval=0.2)
        out["fault_shown_after_s"] = round(time.monotonic() - killed_at, 2)
        sessions = {n: json_lines(logs / f"{n}.out") for n in ("sim", "skill_mgr")}
        mgr = sessions["skill_mgr"]
        out["first_session"] = {"sim": sessions["sim"][0] if sessions["sim"] else None,
                                "skill_mgr": mgr[0] if mgr else None, "first": first}
        messages = [first.get("summary", {}).get("error", "")]
        messages += [s.get("error", "") for s in sessions["sim"][:1] + mgr[:1]]
        messages += [str(t) for s in mgr[:1] for t in s.get("tasks", {}).values()]
        out["fault_messages"] = [m for m in messages if m]

        # The next ClearTable: the session after the faulted one. The faulted session left
        # a physics summary unless the physics was the one killed; once every lockstep
        # program has exited for good (EXITED: a clean end, supervisord does not restart
        # it), either a later session has run, or the faulted session survived the fault
        # and ended with its task, and the trial starts the next one.
        lockstep_programs = ("sim", "wm", "gripper", "skill_mgr", "skills")
        faulted_sessions = 0 if PROCESS == "sim" else 1
        started_next = []

        def next_session_done() -> bool:
            st = launch.status(conf)
            # Quiet: every lockstep program has ended for good, except the killed one,
            # which supervisord restarted and which may wait to join a session that the
            # others ended cleanly (it was killed after the task had ended).
            others = [n for n in lockstep_programs if n != PROCESS]
            killed = st.get(PROCESS, "EXITED") if PROCESS in lockstep_programs else "EXITED"  # (a server runs on)
            if not all(st.get(n) == "EXITED" for n in others) or killed not in ("EXITED", "RUNNING"):
                return False
            if len(json_lines(logs / "sim.out")) > faulted_sessions and killed == "EXITED":
                return True
            if not started_next and len(json_lines(logs / "sim.out")) <= faulted_sessions:
                started_next.append(time.monotonic())
                log("the faulted session ended cleanly: starting the next one")
                launch.ctl(conf, "start", *[n for n in lockstep_programs if st.get(n) == "EXITED"])
            return False

        out["next_done"] = bool(poll_until(next_session_done, 300, interval=1.0))
        out["next_started_by_trial"] = bool(started_next)
        mgr_runs, sim_runs = json_lines(logs / "skill_mgr.out"), json_lines(logs / "sim.out")
        out["sessions"] = len(sim_runs)
        out["next_task"] = [str(t) for t in mgr_runs[-1].get("tasks", {}).values()] if mgr_runs else []
        out["next_session_ok"] = bool(sim_runs) and sim_runs[-1].get("ok")
        physics = sim_runs[-1].get("objects", {}) if sim_runs else {}
        launch.shutdown(conf)
        where = world_model_after(RUN)
        wm = {label: w["pose"] for label, w in where.items()}
        out["wm_in"] = {label: w["in"] for label, w in where.items()}
    else:
        poll_until(registered, 90, interval=0.5)
        first = subprocess.Popen([sys.executable, "-m", "skillbus.cli", "run", "ClearTable", *ARGS, "--timeout", "150"],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        kill_after = round(rng.uniform(1.0, 30.0), 2)
        out["kill_after_s"] = kill_after
        time.sleep(kill_after)
        victim = pid_of(PROCESS)
        if victim <= 0:  # (os.kill(0) would kill this trial's own process group)
            raise SystemExit(f"{PROCESS} is not running {kill_after} s into ClearTable")
        os.kill(victim, signal.SIGKILL)
        killed_at = time.monotonic()
        log(f"killed {PROCESS} (pid {victim}) {kill_after} s into ClearTable")
        text, _ = first.communicate(timeout=200)
        out["fault_shown_after_s"] = round(time.monotonic() - killed_at, 2)
        out["first_exit"] = first.returncode
        out["fault_messages"] = [line for line in text.splitlines() if re.search(r"Failure|error|Error", line)][-5:]
        out["first_output"] = text[-2500:]
        # Back: the killed program restarted by supervisord, the skills registered again.
        out["restarted"] = bool(poll_until(lambda: pid_of(PROCESS) not in (0, victim), 60, interval=0.2))
        poll_until(registered, 90, interval=0.5)
        code, text = skill_run(240)
        out["next_exit"] = code
        out["next_task"] = [text[-1500:]]
        out["next_session_ok"] = code == 0
        # Where the products are: the physics now, the world model now (a fresh replica).
        seen["sim"] = None
        while bus.handle(0.0):
            pass
        poll_until(lambda: seen["sim"] is not None, 10, interval=0.1, step=bus.handle)
        physics = {o.name: list(o.pose[:3]) for o in seen["sim"].objects} if seen["sim"] else {}
        wmi = WorldModelInterface(bus, "fault-trial", timeout=10.0)
        wmi.sync()
        wm = {}
        out["wm_in"] = {}
        for label, eid in PRODUCTS.items():
            wm[label] = list(world_pose(wmi, eid)[0])
            owner = [r["src"] for r in wmi.get_relations("", "skiros:contain", eid)]
            out["wm_in"][label] = owner[0] if owner else ""
        launch.shutdown(conf)
    out["physics"] = physics
    out["physics_in_bin"] = {n: in_bin(p) for n, p in physics.items()}
    out["wm_vs_physics_m"] = compare(wm, physics)
finally:
    if launch.supervisord_pid(conf):
        launch.shutdown(conf)
print(json.dumps(out), flush=True)
