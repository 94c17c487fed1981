"""The attacks of the security suite (test_security.py), run inside the test's sandbox.

    security_probe.py system RUN_DIR      launch the system (wall clock, with its key and
                                          policy), start ClearTable, probe it from here as
                                          outsiders while it runs, check nothing was applied
                                          and the task succeeded; one JSON line
    security_probe.py outsider            the same probes without a key (run from a second
                                          network namespace: another host); one JSON line

The probes, each as an outsider without the key, with a wrong key, as a replay of genuine
messages captured on the wire, and as a key holder under another program's identity:
commit a world-model element with a NaN pose, move the arm (joint1 to 1.2 rad), pause the
physics, wipe the world with load_scene, forge a world-model change for the replicas.
"""

from __future__ import annotations

import json
import os
import secrets
import subprocess
import sys
import time
from pathlib import Path

from skillbus import auth, launch
from skillbus.bus import AuthenticatedBus, channel, open_raw_bus, resolve_url
from skillbus.msgs import (header_t, joint_traj_point_t, robot_arm_cmd_t, sim_control_t, sim_status_t, wm_change_t,
                           wm_commit_t, wm_op_t, wm_scene_t, wm_txn_t)
from skillbus.rpc import RpcClient, RpcError
from skillbus.system import TASK, programs
from skillbus.waiting import poll_until, wait_until
from skillbus.world import Element
from skillbus.world.convert import op

FORGED_LABEL = "forged-by-probe"
ARGS = [a for kv in TASK.split()[1:] for a in ("-p", kv)]


def forged_element() -> Element:
    e = Element("skiros:Product", FORGED_LABEL)
    e.setProperty("skiros:PositionX", 0.5)
    return e


def arm_cmd(who: str) -> robot_arm_cmd_t:
    m = robot_arm_cmd_t()
    m.header = header_t()
    m.id = f"probe-arm-{who}"
    m.joint_names = ["joint1"]
    m.num_joints = 1
    p = joint_traj_point_t()
    p.time_from_start_ns = 1_000_000_000
    p.positions, p.num_positions = [1.2], 1
    p.velocities, p.num_velocities = [], 0
    m.points, m.num_points = [p], 1
    return m


def probe(bus, who: str) -> dict[str, str]:
    """Every attack over `bus`; what each got back ("no answer" is right: the servers
    dropped the requests)."""
    got = {}
    txn = wm_txn_t()
    txn.header = header_t()
    txn.client_id, txn.request_id, txn.expected_version = f"probe-{who}", 1, -1
    txn.ops = [op(wm_op_t.ADD_ELEMENT, element=forged_element())]
    txn.num_ops = 1
    calls = {
        "wm_commit": ("WM", "commit", txn, wm_commit_t),
        "wm_load_scene": ("WM", "load_scene", wm_scene_t(), wm_scene_t),  # empty Turtle: an empty world
        "sim_pause": ("SIM", "pause", sim_control_t(), sim_status_t),
    }
    for name, (area, method, req, rep) in calls.items():
        try:
            RpcClient(bus, area, f"probe-{who}").call(method, req, rep, timeout=1.0)
            got[name] = "answered"
        except RpcError as e:
            got[name] = "no answer" if "no reply" in str(e) or "no " in str(e) else f"error: {e}"
    bus.publish(channel("SB_ROBOT_ARM_CMD"), arm_cmd(who).encode())
    change = wm_change_t()
    change.header = header_t()
    change.version = 10**9
    change.ops = [op(wm_op_t.ADD_ELEMENT, element=forged_element())]
    change.num_ops = 1
    bus.publish(channel("SB_WM_CHANGES"), change.encode())
    got["published"] = "arm command, world-model change"
    return got


def outsider() -> None:
    # An outsider's own LCM on the other "host": it joins the group on its network card,
    # as a program that is not skillbus would (skillbus's own guard is told so).
    import os
    from skillbus.bus import LcmBus, route_interface
    os.environ["SKILLBUS_NETWORK"] = route_interface(int.from_bytes(bytes([239, 255, 76, 67]), "big"))
    print(json.dumps(probe(LcmBus(resolve_url(None)), "veth")), flush=True)


def sh(*argv: str) -> None:
    r = subprocess.run(argv, capture_output=True, text=True, timeout=30)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)}: {r.stderr.strip()}")


def from_another_host(url: str) -> dict:
    """A second host: a child network namespace joined to ours by a veth pair (we are root
    in the sandbox's user namespace). This side joins the multicast group on its veth end,
    as a robot computer on a shared network does on its interface; the other side sends the
    probes with ttl=1 and no key."""
    import socket
    import struct
    child = subprocess.Popen(["unshare", "-n", "--", "sleep", "600"])
    try:
        # (until the child is in its own network namespace: a veth end moved into it earlier
        # would land in ours, and the "other host" would be this one)
        wait_until(lambda: os.readlink(f"/proc/{child.pid}/ns/net") != os.readlink("/proc/self/ns/net"), 10,
                   "the second host's network namespace", interval=0.01)
        sh("ip", "link", "add", "vrobot", "type", "veth", "peer", "name", "vother", "netns", str(child.pid))
        sh("ip", "addr", "add", "10.77.0.1/24", "dev", "vrobot")
        sh("ip", "link", "set", "vrobot", "up", "multicast", "on")
        inside = ["nsenter", "-t", str(child.pid), "-n", "--"]
        sh(*inside, "ip", "link", "set", "lo", "up")
        sh(*inside, "ip", "addr", "add", "10.77.0.2/24", "dev", "vother")
        sh(*inside, "ip", "link", "set", "vother", "up", "multicast", "on")
        sh(*inside, "ip", "route", "add", "224.0.0.0/4", "dev", "vother")
        group = url.split("//", 1)[1].split(":", 1)[0]
        port = int(url.split(":")[2].split("?")[0])
        member = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        member.setsockopt(socket.IPPROTO_IP, socket.IP_ADD_MEMBERSHIP,
                          struct.pack("4s4s", socket.inet_aton(group), socket.inet_aton("10.77.0.1")))
        # (A raw listener on this host shows the probes really arrive over the veth.)
        seen = []
        raw = open_raw_bus(url)
        raw.subscribe(channel("SB_ROBOT_ARM_CMD"), lambda c, d: seen.append(d))
        env = dict(os.environ, SKILLBUS_BUS_URL=f"udpm://{group}:{port}?ttl=1", SKILLBUS_KEY_FILE="none")
        r = subprocess.run([*inside, sys.executable, __file__, "outsider"], capture_output=True, text=True,
                           timeout=60, env=env)
        poll_until(lambda: any(b"probe-arm-veth" in d for d in seen), 3, step=raw.handle)
        member.close()
        if r.returncode != 0:
            return {"error": r.stderr[-1500:]}
        got = json.loads(r.stdout.strip().splitlines()[-1])
        got["arrived"] = any(b"probe-arm-veth" in d for d in seen)
        return got
    finally:
        child.kill()
        child.wait(10)


def system(run: Path) -> None:
    out: dict = {}
    conf = launch.write_config(run, programs(run, task=None, lockstep=False), lockstep=False)
    launch.start(conf, wait_s=90)
    url = resolve_url(None)
    try:
        def registered() -> bool:
            r = subprocess.run([sys.executable, "-m", "skillbus.cli", "skills"], capture_output=True, text=True,
                               timeout=30)
            return "ClearTable" in r.stdout

        poll_until(registered, 90, interval=0.5)
        task = subprocess.Popen([sys.executable, "-m", "skillbus.cli", "run", "ClearTable", *ARGS, "--timeout", "200"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        # Capture genuine traffic (raw, with its authenticators) to replay it.
        captured: dict[str, bytes] = {}
        raw = open_raw_bus(url)
        for ch in ("SB_ROBOT_ARM_CMD", "SB_WM_REQ", "SB_SKPROC_SKILLS_REQ"):
            raw.subscribe(channel(ch), lambda c, d: captured.setdefault(c, bytes(d)))
        poll_until(lambda: len(captured) == 3, 60, step=raw.handle)
        out["captured"] = sorted(captured)

        # 1. No key at all.
        out["no_key"] = probe(open_raw_bus(url), "nokey")
        # 2. A key of our own (not the deployment's).
        out["wrong_key"] = probe(AuthenticatedBus(open_raw_bus(url), [secrets.token_bytes(32)], "operator"), "wrongkey")
        # 3. Genuine messages played again, at once (within the freshness window).
        for ch, data in captured.items():
            raw.publish(ch, data)
            raw.publish(ch, data)
        out["replayed"] = sorted(captured)
        # 4. The deployment's key, another program's channels: an operator's tool may ask
        #    the servers, but not command the arm or announce changes.
        keys = auth.load_keys(os.environ[auth.KEY_ENV])
        insider = AuthenticatedBus(open_raw_bus(url), keys, "operator")
        insider.publish(channel("SB_ROBOT_ARM_CMD"), arm_cmd("insider").encode())
        change = wm_change_t()
        change.header, change.version = header_t(), 10**9
        change.ops, change.num_ops = [op(wm_op_t.ADD_ELEMENT, element=forged_element())], 1
        insider.publish(channel("SB_WM_CHANGES"), change.encode())
        # 5. From another host: a second network namespace joined by a veth pair.
        # (On DDS the servers talk on loopback only: another host reaches nothing at all,
        # tests/integration/test_two_hosts.py; the multicast case is udpm://'s.)
        out["veth"] = from_another_host(url) if url.startswith("udpm://") else {"transport": "dds"}

        text, _ = task.communicate(timeout=260)
        out["task_exit"] = task.returncode
        out["task_output"] = text[-1500:]
        # What the world and the robot look like now.
        from skillbus.bus import open_bus
        from skillbus.sim.client import SimClient
        from skillbus.world import WorldModelInterface
        bus = open_bus(url)
        wmi = WorldModelInterface(bus, "security-check", timeout=10.0)
        wmi.sync()
        out["forged_elements"] = [e.id for e in wmi.get_elements() if e.label == FORGED_LABEL]
        out["elements"] = len(wmi.get_elements())
        out["sim_paused"] = SimClient(bus, "security-check").status()["paused"]
    finally:
        launch.shutdown(conf)
    logs = run / "logs"

    def summary(name: str) -> dict:
        lines = [ln for ln in (logs / f"{name}.out").read_text().splitlines() if ln.startswith("{")]
        return json.loads(lines[-1]) if lines else {}

    out["rejected"] = {n: summary(n).get("bus_rejected") for n in ("wm", "sim", "skill_mgr", "motion")}
    out["skills_log_dropped"] = (logs / "skills.err").read_text().count("dropped ")
    out["arm_commands_seen_by_sim"] = (logs / "sim.err").read_text().count("probe-arm")
    out["wm_version_touched_by_probe"] = (logs / "wm.err").read_text().count(FORGED_LABEL)
    print(json.dumps(out), flush=True)


def forged_clocks(bus, frames: range) -> None:
    """Stop clocks "from the physics server" for the frames given, each three times (as the
    master ends a session); the first would once have made its sender the master."""
    from skillbus.msgs import lockstep_clock_t
    for frame in frames:
        c = lockstep_clock_t()
        c.header = header_t()
        c.header.frame, c.header.sender = frame, "sim"
        c.frame_period_ns = 20_000_000
        c.participants = sorted(["wm", "skill_mgr", "skills", "gripper"])
        c.num_participants = 4
        c.counts, c.num_counts = [], 0
        c.stop, c.stop_reason = True, "forged stop"
        for _ in range(3):
            bus.publish(channel("SB_LOCKSTEP_CLOCK"), c.encode())


def lockstep(run: Path) -> None:
    """The lockstep system while outsiders (no key, a wrong key, the key under the
    operator's identity) send stop clocks, before the session starts and during it."""
    import threading
    conf = launch.write_config(run, programs(run, task=TASK, lockstep=True), lockstep=True)
    url = resolve_url(None)
    keys = auth.load_keys(launch.bus_security()[auth.KEY_ENV])
    senders = [open_raw_bus(url), AuthenticatedBus(open_raw_bus(url), [secrets.token_bytes(32)], "sim"),
               AuthenticatedBus(open_raw_bus(url), keys, "operator")]
    done = threading.Event()
    sent = [0]

    def forge() -> None:  # from before the first clock until the session has ended
        frame = 0
        while not done.is_set():
            for b in senders:
                forged_clocks(b, range(frame, frame + 1))
                sent[0] += 3
            frame = (frame + 7) % 1600
            time.sleep(0.01)

    t = threading.Thread(target=forge, daemon=True)
    t.start()
    out: dict = {}
    try:
        launch.start(conf, wait_s=90)
        lockstep_programs = ("sim", "wm", "gripper", "skill_mgr", "skills")
        out["ended"] = bool(poll_until(lambda: all(launch.status(conf).get(n) == "EXITED" for n in lockstep_programs),
                                       240, interval=0.5))
    finally:
        done.set()
        t.join(5)
        launch.shutdown(conf)
    logs = run / "logs"

    def summary(name: str) -> dict:
        lines = [ln for ln in (logs / f"{name}.out").read_text().splitlines() if ln.startswith("{") and '"ok"' in ln]
        return json.loads(lines[-1]) if lines else {}

    out["forged_clocks_sent"] = sent[0]
    out["sessions"] = len([ln for ln in (logs / "sim.out").read_text().splitlines() if ln.startswith("{")])
    out["sim"] = {k: summary("sim").get(k) for k in ("ok", "error", "frames", "bus_rejected")}
    out["skill_mgr"] = {k: summary("skill_mgr").get(k) for k in ("ok", "error", "tasks", "bus_rejected")}
    out["wm"] = {k: summary("wm").get(k) for k in ("ok", "error", "bus_rejected")}
    print(json.dumps(out), flush=True)


if __name__ == "__main__":
    if sys.argv[1] == "outsider":
        outsider()
    elif sys.argv[1] == "lockstep":
        lockstep(Path(sys.argv[2]))
    else:
        system(Path(sys.argv[2]))
