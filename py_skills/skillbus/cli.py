"""The `skillbus` command."""

from __future__ import annotations

import argparse
import os
import sys

from skillbus.log import setup_logging
from skillbus import cli_values


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="skillbus", description="skill-based robot control without ROS")
    ap.add_argument("--log-level", default=None, type=str.lower, choices=("debug", "info", "warn", "warning", "error"),
                    help="debug, info, warn or error (default: $SKILLBUS_LOG_LEVEL, else info)")
    ap.add_argument("--network", default=None, metavar="IFACE",
                    help="let the bus join its multicast group on this network interface (default: loopback "
                         "only; docs/security.md)")
    sub = ap.add_subparsers(dest="command", required=True)

    d = sub.add_parser("demo", help="the main job: the robot clears the table (lockstep, under supervisord)")
    d.add_argument("--run-dir", default="runs/demo", help="logs, world model data and the LCM log go here")
    d.add_argument("--json", action="store_true", help="print the result as JSON")
    d.add_argument("--robots", type=int, choices=(1, 2), default=1,
                   help="2: two arms, each with its gripper, CAN bus and skill manager, clear six cubes at once")
    d.add_argument("--bus", choices=("lcm", "dds"), default=None,
                   help="the transport: LCM (udpm://) or Cyclone DDS (dds://; docs/transport.md); default: the one "
                        "$SKILLBUS_BUS_URL names, else LCM")
    d.add_argument("--perception", action="store_true",
                   help="Locate from the scene's depth camera (docs/perception.md) instead of the perfect camera")
    d.add_argument("--seed", type=int, default=None, metavar="N",
                   help="the cubes at random places of the table, from this seed (N >= 0; the scene's \"scatter\", "
                        "docs/scene.md); default: where the scene file puts them")
    d.add_argument("--physics-core", default="auto", metavar="auto|off|N",
                   help="the physics server on a core of its own, every other program on the others under the "
                        "batch scheduling policy (taskset, chrt), idle cores polling while it runs where this user "
                        "may ask the kernel (/dev/cpu_dma_latency; docs/pick_and_place.md): auto (the last usable "
                        "core; nothing with one core), off (the kernel places them), or the core's number; "
                        "default auto")
    ls = sub.add_parser("lockstep-session", help="a lockstep session of demo participants without physics")
    ls.add_argument("--frames", type=cli_values.count, default=1000)
    ls.add_argument("--python", type=cli_values.count, default=3, help="Python participants")
    ls.add_argument("--cpp", type=cli_values.count, default=1, help="C++ participants")
    ls.add_argument("--timeout", type=cli_values.seconds, default=120.0, help="seconds before the run is abandoned")
    ls.add_argument("--json", action="store_true", help="print the summary as JSON")
    la = sub.add_parser("launch", help="start the system under supervisord")
    la.add_argument("--run-dir", default="runs/launch")
    la.add_argument("--wall-clock", action="store_true", help="as on a robot: no lockstep, processes restart")
    la_task = la.add_mutually_exclusive_group()  # (--task X --no-task dropped X without a word)
    la_task.add_argument("--task", default=None, type=nonempty_task,
                         help="a task for the manager's first tick (default: ClearTable)")
    la_task.add_argument("--no-task", action="store_true", help="start no task (run them with skillbus run)")
    sd = sub.add_parser("shutdown", help="stop a launched system")
    sd.add_argument("--run-dir", default="runs/launch")
    sp = sub.add_parser("spy", help="lcm-spy with every skillbus message type decodable")
    sp.add_argument("--url", default=None)
    rc = sub.add_parser("record", help="record every message of the bus (LCM or DDS) into an LCM log file, "
                                       "losing none under load (lcm-logger drops when its queue of 30 fills)")
    rc.add_argument("file", help="the LCM log to write")
    rc.add_argument("--url", default=None, help="the bus (default: $SKILLBUS_BUS_URL)")
    rc.add_argument("--seconds", type=cli_values.seconds, default=None,
                    help="stop after this long (default: at SIGINT or SIGTERM)")
    dr = sub.add_parser("dds-record", help="record every skillbus channel of a DDS domain into an LCM log file")
    dr.add_argument("file", help="the LCM log to write")
    dr.add_argument("--url", default=None, help="the DDS bus (default: $SKILLBUS_BUS_URL)")
    dr.add_argument("--seconds", type=cli_values.seconds, default=None,
                    help="stop after this long (default: at SIGINT or SIGTERM)")
    rp = sub.add_parser("replay", help="play a recorded LCM log back onto the bus")
    rp.add_argument("log")
    rp.add_argument("--url", default=None)
    rp.add_argument("--speed", type=cli_values.positive, default=1.0)
    rp.add_argument("--channels", default=None, help="a regular expression of the channels to play")

    p = sub.add_parser("lockstep-participant", help="run a demo lockstep participant")
    p.add_argument("--name", required=True)
    p.add_argument("--url", default=None, help="bus URL (default: $SKILLBUS_BUS_URL or udpm default)")
    p.add_argument("--wall-clock", action="store_true", help="run on the wall clock, without a master")
    p.add_argument("--frames", type=cli_values.count, default=None, help="wall-clock mode: stop after this many frames")
    p.add_argument("--bare", action="store_true", help="no demo traffic: only the lockstep protocol")
    p.add_argument("--listen", action="store_true", help="with --bare: hear (and fold) SB_DEMO_CMD, publish nothing")
    p.add_argument("--every", type=cli_values.at_least_one, default=1, help="test: publish SB_DEMO_CMD in every N-th frame only")
    p.add_argument("--latest-every", type=cli_values.at_least_one, default=None,
                   help="test: read only the newest SB_DEMO_STATE (latest-only) and act in every N-th frame")
    p.add_argument("--drop-at-frame", type=int, default=-1, help="test: lose this frame's output")
    p.add_argument("--slow-at-frame", type=int, default=-1, help="test: take --slow-s seconds over this frame")
    p.add_argument("--slow-s", type=cli_values.seconds, default=0.8, help="test: how long the slow frame takes (s)")
    p.add_argument("--lose-acks-every", type=int, default=0, help="test: lose every N-th ack")
    p.add_argument("--clock-timeout", type=cli_values.seconds, default=10.0)
    p.add_argument("--message-timeout", type=cli_values.seconds, default=2.0)
    hub = sub.add_parser("can-hub", help="run a virtual SocketCAN bus (a hub on a Unix socket)")
    hub.add_argument("--channel", default="vcan0", help="a name (socket under $SKILLBUS_CAN_DIR) or a socket path")
    hub.add_argument("--queue-limit", type=int, default=20000, help="records queued per client before back-pressure")
    hub.add_argument("--stall-timeout", type=cli_values.seconds, default=2.0,
                     help="disconnect a client that takes nothing for this long while over its queue limit")
    dev = sub.add_parser("gripper-device", help="the simulated CANopen (CiA 402) gripper, standalone")
    dev.add_argument("--channel", default="vcan0")
    dev.add_argument("--interface", default="skillbus_vcan", help="python-can interface (socketcan on real CAN)")
    dev.add_argument("--node-id", type=cli_values.node_id, default=5)
    dev.add_argument("--eds", default=None)
    dev.add_argument("--object-width", type=cli_values.non_negative, default=None,
                     help="um: an object between the fingers (standalone only: with the physics, its objects are)")
    dev.add_argument("--period-ms", type=cli_values.positive, default=None,
                     help="the device's step on the wall clock, ms (default 10; not with --lockstep: the frames "
                          "step it)")
    dev.add_argument("--lockstep", action="store_true",
                     help="be a lockstep participant driving the physics server's fingers")
    dev.add_argument("--physics", action="store_true",
                     help="wall clock, with the fingers of the physics server (in wall-clock mode)")
    dev.add_argument("--name", default="gripper", help="lockstep participant name")
    dev.add_argument("--robot", default=None, metavar="NAME",
                     help="the robot whose fingers it drives (channels NAME/SB_SIM_GRIPPER_CMD, NAME/SB_CAN_SYNC)")
    dev.add_argument("--url", default=None, help="bus URL (lockstep)")
    rec = sub.add_parser("can-record", help="record a CAN bus to a candump log file")
    rec.add_argument("file", help="where to write (.log: candump format)")
    rec.add_argument("--channel", default="vcan0")
    rec.add_argument("--interface", default="skillbus_vcan", help="python-can interface (socketcan on real CAN)")
    rec.add_argument("--seconds", type=cli_values.seconds, default=None,
                     help="stop after this long (default: at SIGINT)")
    cl = sub.add_parser("can-log", help="print a candump log decoded as CANopen")
    cl.add_argument("file")
    cl.add_argument("--node-id", type=cli_values.node_id, default=5)
    cl.add_argument("--eds", default=None, help="the device's EDS (default: the skillbus gripper's)")
    cl.add_argument("--json", action="store_true",
                    help="print a JSON list of the frames: time, COB-ID, data and what it means")
    from skillbus import key_cli
    key_cli.add_parser(sub)
    from skillbus.world import cli as wm_cli
    wm_cli.add_parser(sub)
    from skillbus.sim import cli as sim_cli
    sim_cli.add_parsers(sub)
    from skillbus.skill import cli as skill_cli
    skill_cli.add_parsers(sub)
    from skillbus.planning import cli as plan_cli
    plan_cli.add_parser(sub)
    from skillbus.console import cli as console_cli
    console_cli.add_parser(sub)
    from skillbus.skill import tree_view
    tree_view.add_parser(sub)
    from skillbus.generate import cli as generate_cli
    generate_cli.add_parser(sub)
    return ap


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    setup_logging(args.log_level)
    if args.network:  # (read by open_bus here and by every program this command starts)
        os.environ["SKILLBUS_NETWORK"] = args.network
    from skillbus.channels import set_robot, valid_robot_name
    robot = getattr(args, "robot", None)
    if isinstance(robot, str):  # a command's --robot NAME: its robot's channels (skillbus.channels)
        try:
            set_robot(robot)
        except ValueError as e:
            print(f"error: --robot: {e}", file=sys.stderr)
            return 2
    elif os.environ.get("SKILLBUS_ROBOT") and not valid_robot_name(os.environ["SKILLBUS_ROBOT"]):
        print(f"error: $SKILLBUS_ROBOT: robot name {os.environ['SKILLBUS_ROBOT']!r}: a letter, then letters, "
              f"digits or _", file=sys.stderr)
        return 2
    from skillbus.bus import BusError
    from skillbus.rpc import RpcTimeout
    try:
        return profiled(dispatch, args)
    except RpcTimeout as e:  # a server that does not answer: one line naming it, not a traceback
        print(f"error: {e.no_answer()}", file=sys.stderr)
        return 1
    except BusError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    except BrokenPipeError:
        # The reader of our output went away (skillbus skills | head): it read what it
        # wanted. Nothing more may be written to the closed pipe, not even at exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:  # Ctrl-C in a command that has nothing to clean up: no traceback
        print("interrupted", file=sys.stderr)
        return 130
    except OSError as e:
        # A file or folder the command cannot use (a run folder under a file or in /proc,
        # a full disk, no permission), or a wait that timed out: one line naming it, as
        # every command's own errors, not a traceback.
        print(f"error: skillbus {args.command}: {os_error_text(e)}", file=sys.stderr)
        return 1


def nonempty_task(text: str) -> str:
    """A task for launch: a skill type, not empty (--task "" started no task, as --no-task)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("empty: give a skill type, or --no-task")
    return text


def os_error_text(e: OSError) -> str:
    """What went wrong and with which file, in a line.

    >>> os_error_text(FileNotFoundError(2, "No such file or directory", "/proc/nope"))
    "No such file or directory: '/proc/nope'"
    >>> os_error_text(TimeoutError("no answer within 5 s"))
    'no answer within 5 s'
    """
    if e.strerror and e.filename is not None:
        return f"{e.strerror}: {e.filename!r}" + (f" -> {e.filename2!r}" if e.filename2 is not None else "")
    return str(e) or type(e).__name__


PROFILE_ENV = "SKILLBUS_PROFILE_DIR"


def profiled(fn, args: argparse.Namespace) -> int:
    """fn(args), under cProfile when $SKILLBUS_PROFILE_DIR names a folder: the statistics go
    to DIR/<command>-<identity or pid>.prof when the command ends (docs/benchmarks.md, "Where
    the demo's time goes"; read them with `python -m pstats`). The times are the process's
    CPU time, not the wall clock: on a loaded machine a call that wakes another process
    (a publish) is often preempted by it, which the wall clock would blame on the call."""
    folder = os.environ.get(PROFILE_ENV)
    if not folder:
        return fn(args)
    import cProfile
    import time
    prof = cProfile.Profile(time.process_time)
    try:
        return prof.runcall(fn, args)
    finally:
        os.makedirs(folder, exist_ok=True)
        who = os.environ.get("SKILLBUS_IDENTITY") or str(os.getpid())
        prof.dump_stats(os.path.join(folder, f"{args.command}-{who}.prof"))


def dispatch(args: argparse.Namespace) -> int:
    if args.command == "key":
        from skillbus import key_cli
        return key_cli.main(args)
    if args.command == "demo":
        from skillbus import demo
        return demo.main(args)
    if args.command == "lockstep-session":
        from skillbus import lockstep_session
        return lockstep_session.main(args)
    if args.command == "launch":
        from skillbus import launch
        if args.task is None:
            from skillbus.system import TASK
            args.task = TASK
        return launch.main_launch(args)
    if args.command == "plan":
        from skillbus.planning import cli as plan_cli
        return plan_cli.main(args)
    if args.command == "tree":
        from skillbus.skill import tree_view
        return tree_view.main(args)
    if args.command == "generate":
        from skillbus.generate import cli as generate_cli
        return generate_cli.main(args)
    if args.command == "console":
        from skillbus.console import cli as console_cli
        return console_cli.main(args)
    if args.command == "record":
        from skillbus import record
        return record.main(args)
    if args.command == "dds-record":
        from skillbus import dds_record
        return dds_record.main(args)
    if args.command in ("spy", "replay"):
        from skillbus import monitor
        return monitor.main_spy(args) if args.command == "spy" else monitor.main_replay(args)
    if args.command == "shutdown":
        from skillbus import launch
        return launch.main_shutdown(args)
    if args.command in ("skills-process", "skills", "run", "watch", "stop", "pause", "resume", "step"):
        from skillbus.skill import cli as skill_cli
        return skill_cli.main(args)
    if args.command == "gripper-device":
        from skillbus.can import device
        return device.main(args)
    if args.command == "can-record":
        from skillbus.can import canlog
        return canlog.main_record(args)
    if args.command == "can-log":
        from skillbus.can import canlog
        return canlog.main_log(args)
    if args.command == "can-hub":
        from skillbus.can import hub
        return hub.main(args)
    if args.command == "wm":
        from skillbus.world import cli as wm_cli
        return wm_cli.main(args)
    from skillbus.sim import cli as sim_cli
    if args.command in sim_cli.COMMANDS:
        return sim_cli.main(args)
    if args.command == "lockstep-participant":
        from skillbus import lockstep_demo
        return lockstep_demo.main(args)
    return 2


if __name__ == "__main__":
    sys.exit(main())
