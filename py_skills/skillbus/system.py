"""The pick-and-place system: every process, its command line, and the task.

One description serves the supervisord configuration (which ``skillbus launch``,
py_skills/skillbus/launch.py, writes into the run folder as supervisord.conf), the demo,
the tests and the benchmarks, so they all run the same system. Under lockstep the
physics server is the clock master and the world model server, the skill manager, the
skill process and the gripper device are its participants; the CAN hub and the motion
service are plain servers.
"""

from __future__ import annotations

import shlex
import sys
from dataclasses import dataclass, field
from pathlib import Path

from skillbus import paths

PARTICIPANTS = ["wm", "skill_mgr", "skills", "gripper"]
MAP_ACK_TIMEOUT_MS = 60_000  # how long the physics waits for the map's ack of a frame
TASK = ("ClearTable Gripper=skiros:Gripper-7 Arm=skiros:Arm-8 Table=skiros:Table-1 Bin=skiros:Bin-5")
LIBRARIES = ["skillbus.skills.gripper", "skillbus.skills.manipulation", "skillbus.skills.planning"]

# Several robots (docs/pick_and_place.md, "Two arms"): the scene with two arms, each at its
# own table with its own bin, and the region (table, bin) each one clears. An arm keeps to
# its region, so the arms never meet; each robot has its own skill manager, skill
# process, gripper device, CAN bus and motion service, and one world model and one
# physics server serve both.
TWO_ARMS_SCENE = "two_arms.scene.json"
TWO_ARMS_REGIONS = {"r1": ("table1", "bin1"), "r2": ("table2", "bin2")}
ROBOT_PARTS = ["skill_mgr", "skills", "gripper"]  # a robot's lockstep participants, as <robot>_<part>


@dataclass
class Program:
    name: str
    argv: list[str]
    participant: bool = False
    env: dict[str, str] = field(default_factory=dict)

    def command(self) -> str:
        return " ".join(shlex.quote(a) for a in self.argv)


# Frames of 20 ms (10 physics steps of 2 ms): the skills tick at 25 Hz of sim time, the
# gripper and the arm interface run at 50 Hz, and every frame costs each participant a
# wake-up and a round trip; at 10 ms frames the demo spends more time in those than in
# the physics (docs/pick_and_place.md, "Figures").
FRAME_MS = 20.0


def locate_camera(scene: Path, perception: bool) -> list[str]:
    """The skill process's camera interfaces for a scene: the perfect camera (the physics
    server's detections by name) always, and with `perception`, when the scene has a fixed
    depth camera, that camera (the first), which Locate then uses (docs/perception.md,
    "Locate")."""
    import json
    out = ["--interface", "camera=skillbus.robot.camera"]
    if not perception:
        return out
    out += ["--interface", "map=skillbus.perception.map_client"]
    cameras = [c for c in json.loads(Path(scene).read_text()).get("cameras", []) if not c.get("robot")]
    if cameras:
        c = cameras[0]
        out += ["--interface", f"depth_camera=skillbus.perception.depth_camera:{c['name']}:{c.get('noise_stddev_m', 0)}"]
    return out


def programs(run_dir: Path, scene: Path | None = None, task: str | None = TASK, lockstep: bool = True,
             stop_after_task: bool = True, extra_sim: tuple[str, ...] = (), frame_ms: float = FRAME_MS,
             perception: bool = False, manip: bool = False) -> list[Program]:
    """The processes, in start order. `manip`: the skill process also serves the
    manipulation-command skills (skillbus.manip.library) with their articulation and
    attach interfaces. `task` is started at the manager's first tick.
    Every path is absolute: supervisord runs the programs in the repository's folder,
    not where the run folder was named."""
    run_dir = Path(run_dir).resolve()
    scene = Path(scene or paths.demo_scene()).resolve()
    ttl = scene.with_suffix("").with_suffix(".ttl") if scene.name.endswith(".scene.json") else scene.with_suffix(".ttl")
    can = str(paths.socket_path(run_dir, "gripper0.sock"))
    py = [sys.executable, "-m", "skillbus.cli"]
    sim = [str(paths.binary("sim_server")), "--scene", str(scene), "--frame-ms", str(frame_ms)]
    if lockstep:
        sim.append("--pipeline")
    if lockstep:
        # With perception the occupancy map is a participant (its answers as of a frame).
        sim += ["--participants", ",".join(PARTICIPANTS + (["map"] if perception else [])), "--join-timeout-ms", "60000"]
        if perception:
            # The map inserts a whole depth capture in one frame: about 2 s on an idle 2-core
            # machine, several on a busy one. The others are still declared dead after 5 s.
            sim += ["--ack-timeout-ms-of", f"map={MAP_ACK_TIMEOUT_MS}"]
    else:
        sim += ["--wall-clock"]
    sim += list(extra_sim)
    clock = [] if lockstep else ["--wall-clock"]
    mgr = [str(paths.binary("skill_mgr")), *clock, "--tick-timeout-ms", "2000"]
    if task:
        mgr += ["--start", task]
        if lockstep and stop_after_task:  # the task's end ends the session (10 frames of grace), through lockstep
            mgr += ["--end-session-after-task", "10"]
    # The robot interfaces, each named: the arm and the cameras (the robot's channels and
    # the depth camera's, which the physics server or real drivers serve) and the CANopen
    # gripper. A camera is its own interface, not implied by --arm: a robot may have an
    # arm without a camera, or a camera from another driver.
    skills = [*py, "skills-process", "--name", "skills", "--world-model", "--arm", *locate_camera(scene, perception),
              "--gripper", f"{can}:5"]
    for lib in LIBRARIES:
        skills += ["--library", lib]
    if manip:
        skills += ["--library", "skillbus.manip.library", "--interface", "articulation=skillbus.robot.articulation",
                   "--interface", "attach=skillbus.sim.attach"]
    if lockstep:
        skills.append("--lockstep")
    device = [*py, "gripper-device", "--channel", can, "--node-id", "5", "--name", "gripper"]
    device += ["--lockstep"] if lockstep else ["--physics"]
    mapper = [Program("map", [str(paths.binary("map_server")),
                              *(["--lockstep", "map", "--exit-with-session"] if lockstep else []),
                              "--maps", str(run_dir)], participant=lockstep)] if perception else []
    return [
        Program("can_hub", [*py, "can-hub", "--channel", can]),
        Program("sim", sim),
        Program("motion", [str(paths.binary("motion_server")), "--scene", str(scene), *(["--map"] if perception else [])]),
        *mapper,
        Program("wm", [str(paths.binary("wm_server")), *clock, "--data", str(run_dir / "wm"), "--scene", str(ttl)],
                participant=True),
        Program("gripper", device, participant=True),
        Program("skill_mgr", mgr, participant=True),
        Program("skills", skills, participant=True),
    ]


def robots_programs(run_dir: Path, robots: int = 2, lockstep: bool = True, stop_after_task: bool = True,
                    frame_ms: float = FRAME_MS) -> list[Program]:
    """The system with several robots (two_arms.scene.json; only 2 for now), in start order:
    per robot a CAN hub, a motion service, a gripper device, a skill manager (which starts
    ClearTable on its region at its first tick) and a skill process, all with --robot; one
    world model and one physics server. Participant and program names are <robot>_<part>.
    Under lockstep the session ends once every manager's task has ended."""
    if robots != 2:
        raise ValueError(f"{robots} robots: the scenes have one (demo.scene.json) or two (two_arms.scene.json)")
    from skillbus.sim.scene import element_ids
    run_dir = Path(run_dir).resolve()
    scene = (paths.REPO_ROOT / "deploy" / "scenes" / TWO_ARMS_SCENE).resolve()
    ttl = scene.with_suffix("").with_suffix(".ttl")
    ids = element_ids(scene)
    py = [sys.executable, "-m", "skillbus.cli"]
    names = list(TWO_ARMS_REGIONS)
    participants = ["wm"] + [f"{r}_{part}" for r in names for part in ROBOT_PARTS]
    clock = [] if lockstep else ["--wall-clock"]
    sim = [str(paths.binary("sim_server")), "--scene", str(scene), "--frame-ms", str(frame_ms)]
    if lockstep:
        sim += ["--pipeline", "--participants", ",".join(participants), "--join-timeout-ms", "60000"]
        if stop_after_task:
            sim += ["--end-when-asked-by", ",".join(f"{r}_skill_mgr" for r in names)]
    else:
        sim += ["--wall-clock"]
    progs = [Program(f"can_hub_{r}", [*py, "can-hub", "--channel", str(paths.socket_path(run_dir, f"{r}_gripper.sock"))]) for r in names]
    progs.append(Program("sim", sim))
    progs += [Program(f"motion_{r}", [str(paths.binary("motion_server")), "--scene", str(scene), "--robot", r])
              for r in names]
    progs.append(Program("wm", [str(paths.binary("wm_server")), *clock, "--data", str(run_dir / "wm"),
                                "--scene", str(ttl)], participant=True))
    for r in names:
        can = str(paths.socket_path(run_dir, f"{r}_gripper.sock"))
        table, bin_ = TWO_ARMS_REGIONS[r]
        task = (f"ClearTable Gripper={ids[f'{r}_gripper']} Arm={ids[f'{r}_arm']} Table={ids[table]} "
                f"Bin={ids[bin_]}")
        mgr = [str(paths.binary("skill_mgr")), *clock, "--robot", r, "--name", f"{r}_skill_mgr",
               "--tick-timeout-ms", "2000", "--start", task]
        if lockstep and stop_after_task:
            mgr += ["--end-session-after-task", "10"]
        skills = [*py, "skills-process", "--robot", r, "--name", f"{r}_skills", "--world-model", "--arm",
                  "--interface", "camera=skillbus.robot.camera", "--gripper", f"{can}:5"]
        for lib in LIBRARIES:
            skills += ["--library", lib]
        if lockstep:
            skills.append("--lockstep")
        device = [*py, "gripper-device", "--robot", r, "--channel", can, "--node-id", "5", "--name", f"{r}_gripper"]
        device += ["--lockstep"] if lockstep else ["--physics"]
        progs += [Program(f"{r}_gripper", device, participant=True),
                  Program(f"{r}_skill_mgr", mgr, participant=True),
                  Program(f"{r}_skills", skills, participant=True)]
    return progs


def start(box, progs: list[Program], run_dir: Path, timeout: float = 10.0) -> dict:
    """Starts the programs in a sandbox (skillbus.netns.Sandbox) in order; a CAN hub's
    socket must exist before the processes that open the CAN bus start. Returns the
    processes by name."""
    from skillbus.waiting import wait_until
    procs = {}
    for p in progs:
        proc = procs[p.name] = box.start(p.name, p.argv, env=p.env or None)
        if p.name.startswith("can_hub"):
            sock = Path(p.argv[p.argv.index("--channel") + 1])
            wait_until(sock.exists, timeout, f"the CAN hub's socket {sock}", interval=0.02,
                       diagnostic=lambda: f"the end of the CAN hub's stderr:\n{proc.stderr()[-1000:]}")
    return procs
