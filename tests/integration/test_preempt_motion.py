"""Stopping a task stops the robot: `skillbus stop N` during MoveArm must leave the arm
where it is, not let it go on to the target. The whole system on the wall clock (as on a
robot), every part a real process, in the test's sandbox.

The scenario runs inside the sandbox (this file, run as a script); it prints one JSON line.
`stop_during_motion()` is the reusable part: start a skill, wait until the tool moves,
stop the task by a callable (an RPC here; a SIGINT to `skillbus run` works the same way),
and measure how far the tool goes after the stop was acknowledged.
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

from skillbus.skill import State
from typing import Callable

ARM_PARAMS = {"Arm": "skiros:Arm-8", "Target": "skiros:Bin-5", "Height": "0.45"}
MAX_MOTION_AFTER_STOP_M = 0.02


def _dist(a, b) -> float:
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def wait_for_skill(client, skill: str, timeout: float = 60.0) -> bool:
    from skillbus.rpc import RpcError
    from skillbus.skill.cli import skill_list
    from skillbus.waiting import poll_until
    return bool(poll_until(lambda: any(d.type == skill for d in skill_list(client).skills), timeout, interval=0.2,
                           step=client.bus.handle, retry_on=(RpcError,)))


def tool_position(s) -> tuple:
    return tuple(s.tool_pose[:3])


def finger_width(s) -> tuple:
    return (s.finger_width,)


def stop_during_motion(bus, start: Callable[[], int], stop: Callable[[int], None], moving_m: float = 0.15,
                       settle_s: float = 1.0, timeout: float = 60.0, probe: Callable = tool_position) -> dict:
    """Starts a task with `start()` (returns its task id), waits until the robot has moved
    `moving_m` from where it was, stops the task with `stop(task)` (returns once the stop
    is acknowledged), then follows the physics state for `settle_s` of sim time.
    Returns the motion after the acknowledgement and the task's final result (from
    SB_SKILL_PROGRESS; waits for it up to `timeout` s). What moves is `probe(sim_state)`:
    the tool's position (default) or the fingers' width (`finger_width`), in m."""
    from skillbus.bus import channel
    from skillbus.msgs import decode, sim_state_t, skill_progress_t
    from skillbus.waiting import poll_until
    states: list[tuple[float, tuple, str, bool]] = []  # (sim time s, tool xyz, arm command id, arm moving)
    final: dict = {}
    task_box = {"id": None}

    def on_state(ch, data):
        s = decode(sim_state_t, data)
        if s is not None:
            states.append((s.header.sim_time_ns * 1e-9, probe(s), s.arm_command_id, s.arm_moving))

    def on_progress(ch, data):
        p = decode(skill_progress_t, data)
        if p is not None and p.task == task_box["id"] and p.state in (State.Success, State.Failure) and not final:
            final.update(state=int(p.state), message=p.nodes[0].message if p.nodes else "")

    subs = [bus.subscribe(channel("SB_SIM_STATE"), on_state),
            bus.subscribe(channel("SB_SKILL_PROGRESS"), on_progress)]
    out: dict = {}
    try:
        deadline = time.monotonic() + timeout  # for all of it

        def left() -> float:
            return max(0.0, deadline - time.monotonic())

        poll_until(lambda: states, left(), step=bus.handle)
        if not states:
            return {"error": "no physics state"}
        home = states[-1][1]
        task_box["id"] = start()
        out["task"] = task_box["id"]
        poll_until(lambda: final or _dist(states[-1][1], home) >= moving_m, left(), interval=0.005, step=bus.handle)
        if final or _dist(states[-1][1], home) < moving_m:
            return {**out, "error": f"the robot did not move {moving_m} m (task: {final})"}
        t_sent, p_sent = states[-1][0], states[-1][1]
        stop(task_box["id"])
        n_ack = len(states)
        t_ack, p_ack = states[-1][0], states[-1][1]
        # The tool's speed when the stop was sent: the stop came in full motion (at the ack,
        # 60-80 ms of sim time later on a loaded machine, the arm may be slowing down
        # towards its goal already, which says nothing about the stop).
        n_sent = next(i for i in range(len(states) - 1, -1, -1) if states[i][0] <= t_sent)
        prev = next((s for s in reversed(states[:n_sent + 1]) if s[0] <= t_sent - 0.1), states[0])
        out["speed_at_stop_m_s"] = _dist(p_sent, prev[1]) / max(t_sent - prev[0], 1e-9)
        poll_until(lambda: states[-1][0] >= t_ack + settle_s - 1e-6 and final, left(), interval=0.02, step=bus.handle)
        after = [s for s in states[n_ack:]]
        p_end = states[-1][1]
        out.update(
            stop_sent_sim_s=t_sent, stop_acked_sim_s=t_ack, at_ack=list(p_ack), at_end=list(p_end),
            end_sim_s=states[-1][0],
            moved_after_ack_m=_dist(p_end, p_ack),
            max_excursion_after_ack_m=max((_dist(s[1], p_ack) for s in after), default=0.0),
            arm_moving_at_end=states[-1][3], arm_command_at_end=states[-1][2],
            final=final,
        )
        return out
    finally:
        for s in subs:
            bus.unsubscribe(s)


def scenario(run: Path, case: str) -> dict:
    from skillbus.bus import open_bus
    from skillbus.msgs import skill_start_t, skill_task_t
    from skillbus.rpc import RpcClient
    from skillbus.skill.cli import parse_param, skill_list

    skill, params, kw = CASES[case]
    bus = open_bus()
    client = RpcClient(bus, "SKILL", "preempt-test")
    if not wait_for_skill(client, skill):
        return {"error": f"{skill} never registered"}
    lst = skill_list(client)

    def start() -> int:
        req = skill_start_t()
        req.type = skill
        req.params = [parse_param(f"{k}={v}", lst, skill) for k, v in params.items()]
        req.num_params = len(req.params)
        return client.call("start", req, skill_task_t).task

    def stop(task: int) -> None:
        req = skill_start_t()
        req.task = task
        client.call("stop", req, skill_task_t)

    if case == "arm-sigint":
        return sigint_scenario(bus, skill, params, kw)
    out = stop_during_motion(bus, start, stop, **kw)
    if case == "gripper" and "error" not in out:
        out["then_open"] = run_to_end(bus, client, lst, "GripperOpen", {"Gripper": "skiros:Gripper-7"})
    return out


def sigint_scenario(bus, skill: str, params: dict, kw: dict) -> dict:
    """As a user would: `skillbus run` in the foreground, then Ctrl-C (SIGINT). The stop
    counts as acknowledged when the client has exited (it exits after the manager
    acknowledged the stop and the task's end was shown)."""
    import re
    import signal
    import subprocess
    argv = [sys.executable, "-m", "skillbus.cli", "run", skill, *[x for k, v in params.items() for x in ("-p", f"{k}={v}")]]
    client = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    def start() -> int:
        line = client.stdout.readline()  # "task N: MoveArm started"
        m = re.match(r"task (\d+): ", line)
        if not m:
            client.kill()
            raise RuntimeError(f"skillbus run said {line!r}; stderr: {client.stderr.read()[-2000:]}")
        return int(m.group(1))

    def stop(task: int) -> None:
        from skillbus.waiting import poll_until
        client.send_signal(signal.SIGINT)
        # the physics state keeps coming (dispatched meanwhile): the ack is when the client exits
        poll_until(lambda: client.poll() is not None, 30, interval=0.01, step=bus.handle)

    out = stop_during_motion(bus, start, stop, **kw)
    out["client_exit"] = client.wait(timeout=30)
    out["client_output"] = (client.stdout.read() + client.stderr.read())[-2000:]
    return out


def run_to_end(bus, client, lst, skill: str, params: dict, timeout: float = 30.0) -> dict:
    """Runs a skill to its end; its final state and message."""
    from skillbus.bus import channel
    from skillbus.msgs import decode, skill_progress_t, skill_start_t, skill_task_t
    from skillbus.skill.cli import parse_param
    from skillbus.waiting import poll_until
    final: dict = {}
    task = {"id": None}

    def on_progress(ch, data):
        p = decode(skill_progress_t, data)
        if p is not None and p.task == task["id"] and p.state in (State.Success, State.Failure) and not final:
            final.update(state=int(p.state), message=p.nodes[0].message if p.nodes else "")

    sub = bus.subscribe(channel("SB_SKILL_PROGRESS"), on_progress)
    try:
        req = skill_start_t()
        req.type = skill
        req.params = [parse_param(f"{k}={v}", lst, skill) for k, v in params.items()]
        req.num_params = len(req.params)
        task["id"] = client.call("start", req, skill_task_t).task
        poll_until(lambda: final, timeout, step=bus.handle)
        return final or {"error": f"{skill} did not end within {timeout} s"}
    finally:
        bus.unsubscribe(sub)


# skill, its parameters, how to watch it (the fingers start open: 80 mm, closing at 50 mm/s)
CASES = {
    "arm": ("MoveArm", ARM_PARAMS, {"moving_m": 0.15, "probe": tool_position}),
    "arm-sigint": ("MoveArm", ARM_PARAMS, {"moving_m": 0.15, "probe": tool_position}),
    "gripper": ("GripperClose", {"Gripper": "skiros:Gripper-7"}, {"moving_m": 0.01, "probe": finger_width}),
}


def run_case(sandbox, tmp_path, case: str) -> dict:
    from conftest import last_json
    from skillbus.system import programs, start
    run = tmp_path / "run"
    run.mkdir()
    start(sandbox, programs(run, task=None, lockstep=False), run)
    sc = sandbox.start("scenario", [sys.executable, __file__, str(run), case])
    assert sandbox.wait(sc, 240) == 0, sc.stdout()[-3000:] + sc.stderr()[-3000:]
    r = last_json(sc.stdout())
    print(json.dumps(r, indent=1))
    assert "error" not in r, r
    assert r["final"]["state"] == 4 and "preempted" in r["final"]["message"], r
    assert r["end_sim_s"] - r["stop_acked_sim_s"] >= 1.0 - 1e-6, r  # (sums of 20 ms frames)
    return r


def test_stop_during_move_arm_holds_the_arm(sandbox, tmp_path):
    r = run_case(sandbox, tmp_path, "arm")
    assert r["speed_at_stop_m_s"] > 0.2, r  # it was stopped in full motion
    assert r["moved_after_ack_m"] < MAX_MOTION_AFTER_STOP_M, r
    assert not r["arm_moving_at_end"], r  # settled


def test_sigint_to_skillbus_run_during_move_arm_holds_the_arm(sandbox, tmp_path):
    r = run_case(sandbox, tmp_path, "arm-sigint")
    assert r["client_exit"] == 130, r
    assert "Traceback" not in r["client_output"], r["client_output"]
    assert r["speed_at_stop_m_s"] > 0.2, r
    assert r["moved_after_ack_m"] < MAX_MOTION_AFTER_STOP_M, r
    assert not r["arm_moving_at_end"], r


def test_stop_during_gripper_close_stops_the_fingers(sandbox, tmp_path):
    r = run_case(sandbox, tmp_path, "gripper")
    assert r["speed_at_stop_m_s"] > 0.02, r  # closing
    assert r["at_end"][0] > 0.03, r  # nowhere near closed (from 80 mm, stopped after 10 mm)
    assert r["moved_after_ack_m"] < 0.01, r
    # a halted gripper takes the next command
    assert r["then_open"]["state"] == 3, r["then_open"]


if __name__ == "__main__":
    print(json.dumps(scenario(Path(sys.argv[1]), sys.argv[2])), flush=True)
