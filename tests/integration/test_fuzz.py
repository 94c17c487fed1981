"""The fuzz run of issue 14: every process of the pick-and-place system, flooded on every
channel it subscribes to with messages signed with the deployment's key (random bytes,
truncations and bit flips of real messages, absurd values, valid ones) and with messages
that do not authenticate (no trailer, garbage trailers, another key, another channel,
stale, replayed): no crash, no hang.

For each process: start it (and what it needs), flood it (fuzz_publisher.py: bursts, and
after each burst a normal request that it must answer, so the figures are of the process
and not of LCM's queues), then: it is alive, it answers a normal request as before, and
stopped it ends normally with its summary. The figures are printed (pytest -s).

    SKILLBUS_FUZZ_MESSAGES  messages per process (default 20,000; `make fuzz`: 1,000,000)
    SKILLBUS_FUZZ_SEED      the seed (default 2026); a failure names the seed and the
                            messages, replayed with fuzz_publisher.py --start/--show
    SKILLBUS_FUZZ_AVOID     names of fuzz_publisher.KNOWN_BUGS whose messages are left out,
                            to look past a crash found and not fixed yet (never in `make
                            test` or `make fuzz`; the figures say how many were left out)
"""

from __future__ import annotations

import json
import os
import re
import signal
import sys
import time

import pytest

from conftest import last_json, python_tool
from skillbus import netns, paths, system
from skillbus.netns import Sandbox
from skillbus.waiting import poll_until

COUNT = int(os.environ.get("SKILLBUS_FUZZ_MESSAGES", "20000"))
SEED = int(os.environ.get("SKILLBUS_FUZZ_SEED", "2026"))
# The motion service plans with Ceres (milliseconds a plan: 500 messages a second), so the
# short run (`make test`, no SKILLBUS_FUZZ_MESSAGES) gives it a quarter of the others'.
MOTION_COUNT = COUNT if "SKILLBUS_FUZZ_MESSAGES" in os.environ else COUNT // 4
# A flood goes at 500 to 10,000 messages a second: each gets time for 250 a second.
TIMEOUT = 120 + COUNT // 250
PY = [sys.executable, "-m", "skillbus.cli"]

pytestmark = pytest.mark.timeout(TIMEOUT + 60)


def check(sandbox, target: str, *extra: str) -> dict:
    """The target's answer to a normal request (fuzz_publisher.py --check), in a few seconds."""
    c = sandbox.start(f"check-{target}-{time.monotonic_ns()}", python_tool("fuzz_publisher.py", "--target", target,
                                                                          "--check", *extra))
    sandbox.wait(c, 30)
    return last_json(c.stdout())


def flood(sandbox, target: str, watched, *extra: str, count: int = COUNT) -> dict:
    """Floods `target`; fails naming the messages to replay if a watched process died or
    the target stopped answering."""
    fz = sandbox.start(f"fuzz-{target}", python_tool("fuzz_publisher.py", "--target", target, "--count", str(count),
                                                     "--seed", str(SEED), *extra))
    poll_until(lambda: fz.returncode is not None or any(p.returncode is not None for p in watched), TIMEOUT)
    if fz.returncode is None and any(p.returncode is not None for p in watched):
        poll_until(lambda: fz.returncode is not None, 1.0)  # (its probe may name it first)
        sandbox.kill(fz, signal.SIGTERM)  # it stops and says where it was
    rc = sandbox.wait(fz, 40)
    r = last_json(fz.stdout())
    dead = {p.name: p.returncode for p in watched if p.returncode is not None}
    if dead or r["hang"]:
        start = re.search(r"messages (\d+) to (\d+)", r["hang"] or "")
        first = int(start.group(1)) if start else 0
        replay = (f"replay: tests/integration/fuzz_publisher.py --target {target} --seed {SEED} --start {first} "
                  f"--count {r['end'] - first} --burst 1 (one probe per message), or --show {first}:{r['end']}")
        tails = "\n".join(f"--- {p.name} (exit {p.returncode}):\n{p.stderr()[-1500:]}" for p in watched
                          if p.returncode is not None)
        pytest.fail(f"{target}: {'crashed: ' + str(dead) if dead else 'hang'}: {r['hang']}\n{replay}\n{tails}")
    assert rc == 0, fz.stderr()[-2000:]
    return r


def bad_counts(stderr: str) -> dict[str, int]:
    """Bad input a C++ or Python process counted, per channel, from its log (the first five
    of each channel are logged, then every 1000th: a lower bound)."""
    out: dict[str, int] = {}
    for m in re.finditer(r"bad message #(\d+) on (\S+)", stderr):
        out[m.group(2)] = max(out.get(m.group(2), 0), int(m.group(1)))
    return out


def logged_drops(stderr: str) -> int:
    """Messages a Python process's bus refused, from its log ("dropped REASON ... (and N
    more like it)", at most one line per 10 s per reason and sender: a lower bound)."""
    n = 0
    for line in stderr.splitlines():
        if "dropped " in line and ("unsigned" in line or "bad_mac" in line or "stale" in line or "replayed" in line):
            m = re.search(r"\(and (\d+) more like it\)", line)
            n += 1 + (int(m.group(1)) if m else 0)
    return n


def uncaught(stderr: str) -> bool:
    """A traceback that no handler caught: Python's own, over several lines. (A handled one
    is a log record, one line with its new lines escaped: a skill that raised fails, the
    process goes on.)"""
    return re.search(r"^Traceback \(most recent call last\):$", stderr, re.M) is not None


def report(target: str, r: dict, **more) -> None:
    print(f"\nfuzz {target}: {r['sent']:,} messages in {r['seconds']} s ({r['rate']:,}/s), seed {SEED}")
    print(f"  kinds     {json.dumps(r['kinds'])}")
    print(f"  channels  {json.dumps(r['channels'])}")
    print(f"  requests  {r['requests']:,} well-formed signed RPC requests, {r['answered']:,} answered")
    print(f"  probes    {r['probes']:,} (median {r['probe_s']['median'] * 1000:.1f} ms, max "
          f"{r['probe_s']['max'] * 1000:.1f} ms); kernel UDP receive-buffer drops {r['udp_rcvbuf_errors']:,} "
          f"of {r['udp_in_datagrams']:,} datagrams delivered")
    if r.get("skipped_known_bugs"):
        print(f"  SKIPPED   {json.dumps(r['skipped_known_bugs'])} (SKILLBUS_FUZZ_AVOID: known bugs' messages left out)")
    for k, v in more.items():
        print(f"  {k:<9} {json.dumps(v) if not isinstance(v, str) else v}")


def stop(sandbox, proc, sig=signal.SIGTERM, timeout: float = 10.0) -> tuple[int, str]:
    sandbox.kill(proc, sig)
    return sandbox.wait(proc, timeout), proc.stdout()


def assert_cpp_summary(name: str, rc: int, out: str, r: dict, not_heard: tuple[str, ...] = ()) -> dict:
    """Its summary says it ended normally, and its bus refused what came without the key
    (on the channels it listens to: `not_heard` are fuzzed but not subscribed yet)."""
    s = last_json(out)
    assert rc == 0 and s["ok"], f"{name} did not end normally: exit {rc}, {s}"
    unauthenticated = r["unauthenticated"] - sum(r["unauthenticated_by_channel"].get(c, 0) for c in not_heard)
    rejected = sum(s.get("bus_rejected", {}).values())
    # every message without the key reached the process and was refused (a few may be
    # lost in the kernel's buffers, none may be taken)
    assert rejected >= 0.9 * unauthenticated, f"{name} refused {rejected} of {unauthenticated}: {s}"
    return s


def assert_answered(r: dict) -> None:
    # the requests well-formed and signed reached the server and were answered
    assert r["answered"] >= 0.9 * r["requests"], r


def test_wm_server(sandbox, binary, tmp_path):
    wm = sandbox.start("wm", [binary("wm_server"), "--wall-clock", "--data", tmp_path / "wm", "--scene",
                              paths.demo_scene().with_suffix("").with_suffix(".ttl")])
    before = check(sandbox, "wm_server")
    assert before["ok"], before
    r = flood(sandbox, "wm_server", [wm])
    after = check(sandbox, "wm_server")
    assert wm.returncode is None
    assert after["ok"], after
    rc, out = stop(sandbox, wm)
    s = assert_cpp_summary("wm_server", rc, out, r)
    assert_answered(r)
    report("wm_server", r, refused=s.get("bus_rejected"), bad_input=bad_counts(wm.stderr()),
           rejected_txns=s["rejected"], world=f"version {before['version']} -> {after['version']}, "
                                              f"{before['elements']} -> {after['elements']} elements")


def test_skill_mgr(sandbox, binary):
    mgr = sandbox.start("skill_mgr", [binary("skill_mgr"), "--wall-clock"])
    before = check(sandbox, "skill_mgr")
    assert before["ok"], before
    r = flood(sandbox, "skill_mgr", [mgr])
    after = check(sandbox, "skill_mgr")
    assert mgr.returncode is None
    assert after["ok"], after
    rc, out = stop(sandbox, mgr)
    # (its client of the skill process SKILLS subscribes once a process of that area registered and was called)
    s = assert_cpp_summary("skill_mgr", rc, out, r, not_heard=("SB_SKPROC_SKILLS_REP",))
    assert_answered(r)
    report("skill_mgr", r, refused=s.get("bus_rejected"), bad_input=bad_counts(mgr.stderr()),
           tasks=len(s["tasks"]), skills=f"{before['skills']} before, {after['skills']} after (the flood registers)")


def test_sim_server(sandbox, binary):
    sim = sandbox.start("sim", [binary("sim_server"), "--scene", paths.demo_scene(), "--wall-clock"])
    before = check(sandbox, "sim_server")
    assert before["ok"], before
    r = flood(sandbox, "sim_server", [sim])
    after = check(sandbox, "sim_server")
    assert sim.returncode is None
    assert after["ok"], after
    rc, out = stop(sandbox, sim)
    s = assert_cpp_summary("sim_server", rc, out, r)
    assert_answered(r)
    report("sim_server", r, refused=s.get("bus_rejected"), bad_input=s["bad_input"],
           commands=f"{s['commands_accepted']} accepted, {s['commands_rejected']} rejected")


def test_motion_server(sandbox, binary):
    motion = sandbox.start("motion", [binary("motion_server"), "--scene", paths.demo_scene()])
    before = check(sandbox, "motion_server")
    assert before["ok"] and before["plan"]["ok"], before
    r = flood(sandbox, "motion_server", [motion], count=MOTION_COUNT)
    after = check(sandbox, "motion_server")
    assert motion.returncode is None
    assert after["ok"], after
    assert after["plan"] == before["plan"]  # stateless: the same request, the same plan
    rc, out = stop(sandbox, motion)
    s = assert_cpp_summary("motion_server", rc, out, r)
    assert_answered(r)
    report("motion_server", r, refused=s.get("bus_rejected"), bad_input=s["bad_input"], served=s["served"])


def start_hub(sandbox, path):
    hub = sandbox.start("can_hub", [*PY, "can-hub", "--channel", path])
    hub.wait_for("can-hub ", 10, stream="stdout")
    return hub


def test_gripper_device(sandbox, tmp_path):
    sock = tmp_path / "gripper0.sock"
    hub = start_hub(sandbox, sock)
    dev = sandbox.start("gripper", [*PY, "gripper-device", "--channel", sock, "--node-id", "5", "--name", "gripper",
                                    "--physics"])
    dev.wait_for('"physics": true', 30, stream="stdout")
    before = check(sandbox, "gripper_device", "--hub", str(sock))
    assert before["ok"], before
    r = flood(sandbox, "gripper_device", [dev, hub], "--hub", str(sock))
    after = check(sandbox, "gripper_device", "--hub", str(sock))
    assert dev.returncode is None and hub.returncode is None
    assert after["ok"] and after["heartbeat_ms"] == before["heartbeat_ms"], after
    rc, out = stop(sandbox, dev, signal.SIGINT)  # its summary at Ctrl-C
    s = last_json(out)
    assert rc == 0 and not uncaught(dev.stderr()), dev.stderr()[-3000:]
    report("gripper_device", r, bad_input=s["bad_input"], rejected=s["rejected"],
           refused=f"at least {logged_drops(dev.stderr()):,} (from its log)")
    # what it took from the flood that was not sane, it counted
    assert s["bad_input"] > 0.1 * r["signed"], s


def test_skills_process(sandbox, tmp_path):
    """The Python skill process as the system runs it on the wall clock (world model,
    arm, camera and the CAN gripper), with its manager, world model, motion service and
    gripper device beside it."""
    progs = {p.name: p for p in system.programs(tmp_path, task=None, lockstep=False)}
    procs = system.start(sandbox, [progs[n] for n in ("can_hub", "motion", "wm", "gripper", "skill_mgr", "skills")],
                         tmp_path)
    skills = procs["skills"]
    skills.wait_for("registered", 60)
    before = check(sandbox, "skills_process")
    assert before["ok"], before
    r = flood(sandbox, "skills_process", list(procs.values()))
    after = check(sandbox, "skills_process")
    assert all(p.returncode is None for p in procs.values()), {n: p.returncode for n, p in procs.items()}
    assert after["ok"], after
    err = skills.stderr()
    rc, _ = stop(sandbox, skills, signal.SIGINT)  # Ctrl-C: it ends at once, without a traceback
    assert rc == 130 and not uncaught(skills.stderr()), skills.stderr()[-3000:]
    assert_answered(r)
    rejected = re.findall(r"rejected (\S+?): ", err)
    report("skills_process", r, refused=f"at least {logged_drops(err):,} (from its log)",
           rejected=f"{len(set(rejected))} kinds logged (once each)", bad_input=bad_counts(err))


def test_lockstep_participants(tmp_path):
    """The lockstep clock path: a C++ master and a Python and a C++ participant of the demo
    world, flooded on the clock, ack, join, end and the demo's channels. A holder of the
    key may end a session (a clock that says stop, an ack with an error): then every
    process must have ended normally, naming why, and the next session starts; at the
    end of the flood the session in progress (or the next) runs all its frames."""
    frames = 3000
    sessions: list[dict] = []
    with Sandbox(log_dir=tmp_path / "logs") as box:
        binary = paths.binary
        n = [0]

        def start_session():
            n[0] += 1
            k = n[0]
            clock = box.start(f"clock{k}", [binary("sb_clock"), "--demo", "--frames", str(frames), "--participants",
                                            "cpp1,py1", "--ack-timeout-ms", "3000", "--join-timeout-ms", "20000"])
            py1 = box.start(f"py1-{k}", [*PY, "lockstep-participant", "--name", "py1", "--clock-timeout", "5"])
            cpp1 = box.start(f"cpp1-{k}", [binary("sb_demo_participant"), "--name", "cpp1", "--clock-timeout-ms",
                                           "5000"])
            return [clock, py1, cpp1]

        def crashed(procs, fz=None) -> None:
            """Fails naming a process of the session that did not end normally (killed by a
            signal, or no summary), and the messages sent before (the flood stopped)."""
            for p in procs:
                if p.returncode is not None and (p.returncode not in (0, 1) or netns.last_json(p.stdout()) is None):
                    where = ""
                    if fz is not None and fz.returncode is None:
                        box.kill(fz, signal.SIGTERM)
                        box.wait(fz, 40)
                        f = netns.last_json(fz.stdout()) or {}
                        end = f.get("end", 0)
                        where = (f" before message {end} of seed {SEED}: replay its last messages with "
                                 f"fuzz_publisher.py --target lockstep --seed {SEED} --start {max(0, end - 2000)} "
                                 f"--count 2000, or --show")
                    pytest.fail(f"{p.name} crashed under the flood (exit {p.returncode}){where}\n"
                                f"{p.stderr()[-3000:]}")

        def end_session(procs, fz=None) -> dict:
            """Waits for the three (the master ends within its timeouts, the participants
            within theirs); each must end normally with its summary."""
            for p in procs:
                box.wait(p, 30)
                crashed(procs, fz)
            return {p.name.split("-")[0].rstrip("0123456789"): netns.last_json(p.stdout()) for p in procs}

        procs = start_session()
        fz = box.start("fuzz", python_tool("fuzz_publisher.py", "--target", "lockstep", "--count", str(COUNT),
                                           "--seed", str(SEED), "--rate", "5000"))
        def watch() -> bool:
            nonlocal procs
            crashed(procs, fz)
            if procs[0].returncode is not None:  # the session ended (its frames, or a forged stop)
                sessions.append(end_session(procs, fz))
                procs = start_session()
            return fz.returncode is not None

        poll_until(watch, TIMEOUT)
        assert box.wait(fz, 10) == 0, fz.stderr()[-2000:]
        r = last_json(fz.stdout())
        sessions.append(last := end_session(procs))
        if not last["clock"]["ok"]:  # ended by a forged message late in the flood: the next one runs clean
            sessions.append(last := end_session(start_session()))
        assert last["clock"]["ok"] and last["clock"]["frames"] == frames, last
        assert all(s["ok"] and s["frames"] == frames for k, s in last.items() if k != "clock"), last
    ended = [s["clock"]["error"][:90] for s in sessions if not s["clock"]["ok"]]
    report("lockstep", r, sessions=f"{len(sessions)} ({len(sessions) - len(ended)} ran all {frames} frames)",
           frames=sum(s["clock"]["frames"] for s in sessions), ended_by=ended[:5],
           bad_input={k: sum(s[k].get("bad_input", 0) for s in sessions) for k in ("clock", "py", "cpp")})


def test_skill_process_registers_again_without_leaking_a_subscription():
    """Found by the flood: every announcement of the manager that does not list the skill
    process (forged ones too: 86 of 1,500 in a 20,000-message flood) makes it register
    again, and each registration left an RPC client subscribed to SB_SKILL_REP behind: a
    million-message flood would have left thousands, each decoding every reply of the
    manager (a slowdown without end). In one process, on an in-process bus."""
    from skillbus.bus import LcmBus
    from skillbus.msgs import skill_processors_t, skill_register_t, skill_start_t
    from skillbus.rpc import RpcServer
    from skillbus.skill.process import SkillProcess
    from skillbus.skill.processors import all_processors

    known = skill_processors_t()
    known.names = sorted(all_processors())
    known.args = known.summaries = [""] * len(known.names)
    known.num_processors = len(known.names)
    bus = LcmBus("memq://")
    manager = RpcServer(bus, "SKILL")
    manager.add_method("processors", lambda req: known, skill_start_t, skill_processors_t)
    manager.add_method("register", lambda reg: reg, skill_register_t, skill_register_t)
    proc = SkillProcess(bus, "leaky", ["skillbus.skills.gripper"])
    proc.register(timeout=5.0)
    subscriptions = len(bus._subs)
    for _ in range(20):
        proc.register(timeout=5.0)
    assert len(bus._subs) == subscriptions
