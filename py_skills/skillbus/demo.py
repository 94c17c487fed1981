"""``skillbus demo`` (and ``make demo``): the main job. The robot clears the table.

Every part a real process, launched under supervisord as on a robot, in lockstep with the
physics server: the world model server, the skill manager, the skill process (gripper
and manipulation skills), the CANopen gripper device on the virtual CAN bus, the motion
service, the physics server, and an LCM logger recording the run. The skill manager
starts ClearTable at its first tick; the demo shows the skill tree live, and when the
physics server ends the session (a fixed number of frames after the task) it prints the
summary: result, sim time, wall time, real-time factor, where every object ended in the
world model (read back from the world model's journal) and in the physics server, and the
digests. Exit code 0 when the task succeeded and every cube is in the bin in both.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from skillbus import paths
from skillbus.skill.skill import State
from skillbus.waiting import poll_until, wait_until

ENDED = (State.Success, State.Failure)

BIN_CENTRE, BIN_HALF, BIN_TOP = (0.0, 0.6), 0.15, 0.25  # the demo scene's bin (two_arms: each arm's)
BIN_CENTRES = {1: [BIN_CENTRE], 2: [(0.0, 0.6), (0.0, -1.0)]}  # by the number of robots


def _last_json(path: Path) -> dict[str, Any]:
    from skillbus.netns import last_json
    try:
        return last_json(path.read_text()) or {}
    except OSError:
        return {}


MIN_GAP = 0.03  # m: no two objects' centres closer at the end (one pushed into another, or in one place)


def closest_pair(objects: dict[str, list[float]]) -> float:
    """The smallest distance between two objects' centres (m; infinity for fewer than two)."""
    names = sorted(objects)
    return min((math.dist(objects[a][:3], objects[b][:3]) for i, a in enumerate(names) for b in names[i + 1:]),
               default=math.inf)


def in_bin(p: list[float], robots: int = 1) -> bool:
    """Whether the point is inside a bin of the scene (the demo's, or one of two_arms')."""
    return any(abs(p[0] - c[0]) < BIN_HALF and abs(p[1] - c[1]) < BIN_HALF and p[2] < BIN_TOP
               for c in BIN_CENTRES[robots])


class TaskView:
    """One manager's task as the watcher saw it."""

    def __init__(self, robot: str) -> None:
        self.robot = robot
        self.last = ""
        self.final = None   # the task's final progress (Success or Failure)
        self.latest = None  # the last progress seen
        self.task = None


class Watcher:
    """The live skill tree: one line whenever the running path changes, and the task's
    final progress for the tree at the end; with several robots, each manager's (the line
    starts with its robot's name).

    It handles the bus on a thread of its own: LCM reads a datagram only when the bus is
    handled, so a watcher that also waits for other things (the supervisorctl calls that
    tell the demo the session has ended) leaves the socket unread, the kernel's receive
    buffer overflows at several times real time, and progress is lost, the end of the task
    included. Its socket has a large receive buffer too (monitor.watch_url), for the
    moments this thread is not scheduled."""

    def __init__(self, robots: list[str] | None = None) -> None:
        from skillbus.bus import open_bus
        from skillbus.channels import robot_channel
        from skillbus.monitor import watch_url
        self.bus = open_bus(watch_url())
        self.views = [TaskView(r) for r in (robots or [""])]
        self.error: Exception | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._spin, name="watcher", daemon=True)
        for view in self.views:
            self.bus.subscribe(robot_channel("SB_SKILL_PROGRESS", view.robot),
                               lambda ch, data, v=view: self.on_progress(v, data))

    @property
    def final(self):
        """The one robot's task's final progress (the demo with one robot)."""
        return self.views[0].final

    @property
    def latest(self):
        return self.views[0].latest

    def all_final(self) -> bool:
        return all(v.final is not None for v in self.views)

    def on_progress(self, view: TaskView, data: bytes) -> None:
        from skillbus.msgs import decode, skill_progress_t
        p = decode(skill_progress_t, data)
        if p is None:
            return
        if view.task is None:
            view.task = p.task  # the manager's one task (started at its first tick)
        if p.task != view.task or view.final is not None:
            return
        view.latest = p
        if p.state in ENDED:
            view.final = p
        names = {n.id: n for n in p.nodes}
        running = [n for n in p.nodes if n.state == State.Running and n.type]
        if not running:
            return
        leaf = running[-1]
        path, cur = [], leaf
        while cur is not None:
            if cur.type:
                label = cur.type
                obj = next((line.split("=", 1)[1] for line in cur.params.splitlines() if line.startswith("Object=")),
                           "")
                path.append(f"{label}({obj})" if obj and cur.type in ("Pick", "Place") else label)
            cur = names.get(cur.parent)
        line = " > ".join(reversed(path)) + (f": {leaf.message}" if leaf.message else "")
        if line != view.last:
            view.last = line
            who = f"{view.robot}: " if view.robot else ""
            print(f"  t={p.header.sim_time_ns * 1e-9:6.2f} s  {who}{line}", flush=True)

    def start(self) -> "Watcher":
        self._thread.start()
        return self

    def _spin(self) -> None:
        # Signals are for the main thread (it shuts the system down); here they would only
        # interrupt LCM's select (EINTR: lcm_handle_timeout() returns -1).
        signal.pthread_sigmask(signal.SIG_BLOCK, (signal.SIGINT, signal.SIGTERM))
        while not self._stop.is_set():
            try:
                self.bus.handle(0.1)
            except Exception as e:  # (BusError, OSError) reported at the end, never a lost thread
                self.error = e
                return

    def stop(self, wait_final: float = 2.0) -> None:
        """Stops the thread once the task's final progress is in (or wait_final has passed:
        whatever is still in the socket is read first)."""
        poll_until(lambda: self.all_final() or not self._thread.is_alive(), wait_final, interval=0.02)
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(5)


def world_model_after(run_dir: Path) -> dict[str, dict[str, Any]]:
    """Where each product is in the world model, read back from its journal."""
    from skillbus.bus import open_bus
    from skillbus.world import WorldModelInterface
    from skillbus.world.poses import world_pose
    wm = subprocess.Popen([str(paths.binary("wm_server")), "--wall-clock", "--data",
                           str(run_dir / "wm"), "--name", "wm-readback"], stdout=subprocess.DEVNULL,
                          stderr=subprocess.DEVNULL)
    try:
        wmi = WorldModelInterface(open_bus(), "demo-readback", timeout=10.0)
        wmi.sync()
        out = {}
        for e in wmi.get_elements():
            if e.type in ("skiros:Cube", "skiros:Cylinder", "skiros:Product"):
                owner = [r["src"] for r in wmi.get_relations("", "skiros:contain", e.id)]
                where = wmi.get_element(owner[0]) if owner else None
                p, _ = world_pose(wmi, e.id)
                out[e.label] = {"id": e.id, "in": where.label if where else "", "in_type": where.type if where else "",
                                "pose": list(p)}
        return out
    finally:
        wm.terminate()
        wm.wait(10)


DDS_DOMAIN = 42  # the demo's DDS domain (its private network namespace is its own anyway)


def default_transport() -> str:
    """The transport $SKILLBUS_BUS_URL names ("dds" for dds://, else "lcm")."""
    return "dds" if os.environ.get("SKILLBUS_BUS_URL", "").startswith("dds://") else "lcm"


def bus_url(bus: str) -> str:
    """The URL of the demo's bus on that transport: $SKILLBUS_BUS_URL when it names the
    same transport (a test's own domain or port), else the default (udpm://'s, or DDS
    domain 42). `--bus lcm` never inherits a DDS URL, nor `--bus dds` an LCM one."""
    from skillbus.bus import DEFAULT_URL
    env = os.environ.get("SKILLBUS_BUS_URL", "")
    if bus == "dds":
        return env if env.startswith("dds://") else f"dds://{DDS_DOMAIN}"
    return env if env.startswith("udpm://") else DEFAULT_URL


class DemoError(RuntimeError):
    pass


# What marks a folder as a demo's run folder, which the next demo given it clears (a
# launch's own supervisord.conf marks the runs made before the mark was written).
RUN_MARK = ".skillbus-demo-run"
GENERATED_CONF = "; generated by skillbus launch"


def refuse_a_foreign_folder(run_dir: Path) -> None:
    """DemoError unless `run_dir` is empty or a demo's run folder: the demo clears its run
    folder first, and `--run-dir ~/experiments` (or `.`) deleted whatever was there."""
    if not run_dir.is_dir():
        raise DemoError(f"--run-dir {run_dir}: not a folder")
    entries = sorted(p.name for p in run_dir.iterdir())
    if not entries or RUN_MARK in entries:
        return
    conf = run_dir / "supervisord.conf"
    try:
        if conf.read_text(errors="replace").startswith(GENERATED_CONF):
            return
    except OSError:
        pass
    shown = ", ".join(entries[:3]) + (f" and {len(entries) - 3} more" if len(entries) > 3 else "")
    raise DemoError(f"--run-dir {run_dir} holds files that are no demo's ({shown}), and a demo clears its run "
                    "folder first: give a new or empty folder (or one an earlier demo ran in)")


def session_over(conf: Path) -> bool:
    """The physics server (which ends the session) has exited. DemoError when the run's
    supervisord stops answering (killed, or its folder cleared by another demo): nothing
    will say the session ended."""
    from skillbus import launch
    states = launch.status(conf)
    if states:
        return states.get("sim") in ("EXITED", "FATAL", "STOPPED")
    if not paths.socket_path(conf.parent, "supervisor.sock").exists() or not (launch.supervisord_pid(conf) or 0):
        raise DemoError(f"the supervisord of this run ({conf}) no longer answers: its socket or process is gone "
                        "(was the run folder cleared, or supervisord killed?)")
    return False


# Where `--seed N` puts the demo's cubes: anywhere on the table the arm reaches and the
# overhead camera sees, at least 10 cm apart (centres), each turned by a random yaw.
SCATTER = {"on": "table", "region": [0.3, -0.25, 0.65, 0.3], "min_gap": 0.1}


MAX_SEED = 2**32 - 1  # the scene's "scatter" seed (sim_server/scene)


def check_seed(seed: int) -> None:
    if not 0 <= seed <= MAX_SEED:
        raise ValueError(f"--seed {seed}: a seed is a whole number from 0 to {MAX_SEED}")


def scattered_scene(folder: Path, seed: int) -> Path:
    """The demo scene with its cubes at seeded-random places (the scene's "scatter"), and
    its world model file beside it, in `folder`."""
    from skillbus.sim import scene as scenes
    check_seed(seed)
    folder.mkdir(parents=True, exist_ok=True)
    doc = json.loads(paths.demo_scene().read_text())
    doc["scatter"] = {**SCATTER, "seed": seed}
    path = scenes.save(doc, folder / "demo.scene.json", paths.demo_scene())
    (folder / "demo.ttl").write_text(scenes.to_turtle(scenes.load(path)))
    return path


def run(run_dir: Path, quiet: bool = False, bus: str = "lcm", robots: int = 1, perception: bool = False,
        seed: int | None = None, physics_core: str = "auto") -> dict[str, Any]:
    from skillbus import launch
    from skillbus.monitor import mark_log
    from skillbus.system import TWO_ARMS_REGIONS, Program, programs, robots_programs
    if (run_dir / "supervisord.conf").exists() and launch.status(run_dir / "supervisord.conf"):
        # Another demo runs there: clearing the folder would pull its supervisord's socket
        # from under it (it would then wait the whole 15 minutes for a session it no
        # longer sees end).
        raise DemoError(f"{run_dir} is in use: the supervisord of another demo answers there; wait for it to end, "
                        f"stop it (skillbus shutdown {run_dir / 'supervisord.conf'}), or give --run-dir")
    # What it was asked is checked before the folder of the last run is cleared.
    if perception and robots != 1:
        raise ValueError("--perception: the two-arm scene has no depth camera yet")
    if seed is not None and robots != 1:
        raise ValueError("--seed: the two-arm scene's cubes stay where its file puts them")
    if seed is not None:
        check_seed(seed)
    from skillbus import cpu_layout
    cpu_layout.place([], physics_core)  # (a core that cannot be used is named before anything starts)
    if run_dir.exists():
        refuse_a_foreign_folder(run_dir)
        shutil.rmtree(run_dir)
    run_dir.mkdir(parents=True)
    (run_dir / RUN_MARK).write_text("a skillbus demo's run folder: the next demo given it clears it\n")
    scene = scattered_scene(run_dir / "scene", seed) if seed is not None else None
    progs = programs(run_dir, scene=scene, perception=perception) if robots == 1 else robots_programs(run_dir, robots)
    robot_names = [""] if robots == 1 else list(TWO_ARMS_REGIONS)
    participants = [p.name for p in progs if p.participant]
    managers = [p.name for p in progs if p.name.endswith("skill_mgr")]
    # The run's LCM log, by skillbus record on either transport: lcm-logger drops messages
    # when its queue of 30 fills (a busy machine), and a replay then lacks them.
    progs.append(Program("logger", [sys.executable, "-m", "skillbus.cli", "record", str(run_dir / "demo.lcmlog")]))
    layout = cpu_layout.place(progs, physics_core)  # (skillbus.cpu_layout: a core of its own for the physics)
    progs = layout.programs
    if layout.others is not None:
        os.sched_setaffinity(0, layout.others)  # this process's live view, and supervisord, off the physics' core
    url = bus_url(bus)
    os.environ["SKILLBUS_BUS_URL"] = url  # (this process's own bus too: the live view)
    conf = launch.write_config(run_dir, progs, lockstep=True, bus_url=url)
    watcher = None if quiet else Watcher(robot_names).start()
    t0 = time.monotonic()
    logs = run_dir / "logs"
    try:
        launch.start(conf, wait_s=60)  # (shuts down what it started when it fails)
        try:
            wait_until(lambda: session_over(conf), 900 - (time.monotonic() - t0),
                       "the end of the demo's session (15 minutes at most)", interval=0.2)
            poll_until(lambda: not any(launch.status(conf).get(n) == "RUNNING" for n in participants), 30,
                       interval=0.2)
            try:  # the logger has written all of the run before it is stopped
                mark_log(run_dir / "demo.lcmlog")
            except TimeoutError as e:
                print(f"warning: the LCM log may lack the end of the run: {e}", file=sys.stderr)
        finally:
            held = signal.pthread_sigmask(signal.SIG_BLOCK, (signal.SIGINT, signal.SIGTERM))
            try:
                launch.shutdown(conf)
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, held)
    finally:
        if watcher is not None:
            watcher.stop()
    wall = time.monotonic() - t0
    sim = _last_json(logs / "sim.out")
    mgrs = {m: _last_json(logs / f"{m}.out") for m in managers}
    result = {"sim": sim, "mgr": mgrs[managers[0]], "wall_launch_s": wall, "run_dir": str(run_dir), "bus": bus, "url": url,
              "robots": robots, "seed": seed, "cores": layout.note,
              "participants": {n: _last_json(logs / f"{n}.out") for n in participants if n not in managers}}
    result["world_model"] = world_model_after(run_dir)
    for view in watcher.views if watcher is not None else []:
        if (view.final or view.latest) is None:
            continue
        from skillbus.skill.cli import print_tree
        # The task's final progress; only if it never came, the last one seen, said so.
        whose = f" of {view.robot}" if view.robot else ""
        print(f"\nthe skill tree{whose} at the end:" if view.final else
              f"\nthe skill tree{whose} as last seen (the task's final progress was not seen):")
        print_tree(view.final or view.latest)
    if watcher is not None and watcher.error is not None:
        print(f"(the live view stopped early: {watcher.error})")
    tasks = {m: (mgrs[m].get("tasks") or {}).get("1", "no result") for m in managers}
    physics = sim.get("objects", {})
    result["task"] = tasks[managers[0]]
    result["tasks"] = tasks
    result["closest_m"] = closest_pair(physics)
    result["ok"] = (all(t.startswith("Success") for t in tasks.values()) and bool(physics)
                    and all(in_bin(p, robots) for p in physics.values())
                    and result["closest_m"] > MIN_GAP
                    and all(w["in_type"] == "skiros:Bin" for w in result["world_model"].values())
                    and len(result["world_model"]) == len(physics)
                    and sim.get("robot_contact_steps", 0) == 0
                    and not any(sim.get("obstacle_contact_steps", {}).values()))
    return result


def print_summary(r: dict[str, Any]) -> None:
    sim = r["sim"]
    print()
    robots = r.get("robots", 1)
    print("skillbus pick-and-place demo: ClearTable" + (f", {robots} robots" if robots > 1 else ""))
    if robots == 1:
        print(f"  result            {'ok' if r['ok'] else 'FAILED'}: {r['task']}")
    else:
        print(f"  result            {'ok' if r['ok'] else 'FAILED'}")
        for m, t in r["tasks"].items():
            print(f"    {m:16s}{t}")
        print(f"  arms touching     {sim.get('robot_contact_steps', '?')} physics steps (each arm keeps to its region)")
    if r.get("seed") is not None:
        print(f"  cubes             at random places of the table from seed {r['seed']}")
    for name, steps in sim.get("obstacle_contact_steps", {}).items():
        print(f"  arm on {name:11s}{steps} physics steps (the motion service plans around it)")
    frame_ms = 1000 * sim.get("sim_time_s", 0) / max(1, sim.get("frames", 1))
    print(f"  sim time          {sim.get('sim_time_s', 0):.2f} s ({sim.get('frames', 0)} frames of {frame_ms:.0f} ms)")
    print(f"  wall time         {sim.get('wall_time_s', 0):.2f} s (the lockstep session; "
          f"{r['wall_launch_s']:.1f} s with launch and shutdown)")
    print(f"  real-time factor  {sim.get('real_time_factor', 0):.1f}x")
    if r.get("cores"):
        print(f"  cores             {r['cores']}")
    print(f"  closest objects   {100 * r.get('closest_m', 0):.1f} cm apart (centres; at least {100 * MIN_GAP:.0f})")
    print(f"  physics           {sim.get('physics_us_per_step', 0):.0f} us per step ({sim.get('steps', 0)} steps), "
          f"{sim.get('collision_detector', '?')} collision detector")
    print("  objects           world model                      physics server (x, y, z)")
    for name, p in sorted(sim.get("objects", {}).items()):
        w = r["world_model"].get(name, {})
        where = f"in {w.get('in', '?')} ({w.get('id', '?')})"
        print(f"    {name:8s}        {where:32s} ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f})"
              f"{'  in a bin' if in_bin(p, robots) else '  NOT in a bin'}")
    print(f"  state digest      {sim.get('state_digest')}")
    print(f"  session digest    {sim.get('session_digest')}")
    if r.get("bus", "lcm") == "lcm":
        print(f"  LCM log           {Path(r['run_dir']) / 'demo.lcmlog'} (skillbus replay; skillbus spy)")
    else:
        print(f"  bus               Cyclone DDS, {r.get('url', '')}")
        print(f"  LCM log           {Path(r['run_dir']) / 'demo.lcmlog'} (recorded by skillbus record; "
              f"skillbus replay plays it on LCM)")
    print(f"  logs              {Path(r['run_dir']) / 'logs'}")


class Interrupted(Exception):
    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _raise_interrupted(signum, frame):
    raise Interrupted(signum)


def main(args) -> int:
    if not os.environ.get("SKILLBUS_NETNS"):
        # LCM multicast stays inside a private network namespace (docs/transport.md).
        netns = paths.REPO_ROOT / "deploy" / "netns-run"
        from skillbus.monitor import run_foreground
        # (the global options too: --log-level was dropped on the way in)
        log_level = ["--log-level", args.log_level] if getattr(args, "log_level", None) else []
        if getattr(args, "network", None):  # (it was dropped without a word)
            print("error: demo --network: the demo's bus is in a private network namespace of its own, on no "
                  "network interface", file=sys.stderr)
            return 2
        return run_foreground([str(netns), sys.executable, "-m", "skillbus.cli", *log_level, "demo", "--run-dir",
                               str(Path(args.run_dir).resolve()), "--bus", getattr(args, "bus", None) or default_transport(),
                               "--robots", str(getattr(args, "robots", 1))]
                              + (["--json"] if args.json else [])
                              + (["--perception"] if getattr(args, "perception", False) else [])
                              + (["--seed", str(args.seed)] if getattr(args, "seed", None) is not None else [])
                              + ["--physics-core", getattr(args, "physics_core", "auto")])
    # Ctrl-C and SIGTERM end the demo through its clean-up: the system is shut down.
    old = {sig: signal.signal(sig, _raise_interrupted) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        bus = getattr(args, "bus", None) or default_transport()
        robots = getattr(args, "robots", 1)
        print(f"skillbus demo: launching the pick-and-place system under supervisord (lockstep, "
              f"{'Cyclone DDS' if bus == 'dds' else 'LCM'}{f', {robots} robots' if robots > 1 else ''}) ...",
              flush=True)
        try:
            r = run(Path(args.run_dir), bus=bus, robots=robots, perception=getattr(args, "perception", False),
                    seed=getattr(args, "seed", None), physics_core=getattr(args, "physics_core", "auto"))
        except Interrupted as e:
            print(f"\ninterrupted ({e}): the system was shut down", file=sys.stderr)
            return 128 + e.signum
        except (RuntimeError, TimeoutError, ValueError) as e:  # (a launch that failed names the program and shows its log)
            print(f"error: {e}", file=sys.stderr)
            return 1
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)
    if args.json:
        print(json.dumps(r))
    else:
        print_summary(r)
    return 0 if r["ok"] else 1
