"""Command-line parts for the physics server: ``skillbus sim ...``, ``skillbus sim-script``
and ``skillbus scene check|turtle`` (which run sb_scene, the C++ reader and Turtle writer)."""

from __future__ import annotations

import argparse
import json
import sys
from skillbus import cli_values

COMMANDS = ("sim", "sim-script", "scene", "camera", "map")


def add_parsers(sub) -> None:
    s = sub.add_parser("sim", help="the physics server's control services (status, reset, ...)")
    s.add_argument("action", choices=["status", "digest", "reset", "load-scene", "pause", "resume"])
    s.add_argument("scene", nargs="?", default="", help="load-scene: a scene's name in the server's scenes folder (sim_server --scenes; "
                        "by default the folder of its --scene file), e.g. demo")
    s.add_argument("--url", default=None)
    s.add_argument("--timeout", type=cli_values.seconds, default=5.0)
    s.add_argument("--json", action="store_true", help="JSON also for digest (status and the others always are)")

    p = sub.add_parser("sim-script", help="play a command script against the physics server (lockstep)")
    p.add_argument("script", help="JSON: {\"steps\": [{\"at_s\": 0.5, \"arm\"|\"gripper\": {...}}]}")
    p.add_argument("--name", default="script")
    p.add_argument("--url", default=None)
    p.add_argument("--out", default=None, help="write the recorded states and replies here (JSON)")
    p.add_argument("--clock-timeout", type=cli_values.seconds, default=10.0)
    p.add_argument("--robot", default=None, metavar="NAME",
                   help="the robot the script drives (its channels NAME/SB_ROBOT_..., NAME/SB_SIM_...)")

    cam = sub.add_parser("camera", help="a depth camera's capture: ask for one (wall clock) or wait for the next")
    cam.add_argument("action", choices=["capture"])
    cam.add_argument("camera", help="the camera's name in the scene (its \"cameras\")")
    cam.add_argument("--out", default=None, help="write the returns (world frame) here: .ply (ASCII) or .npy "
                                                 "(the organized cloud, height x width x 3, optical frame)")
    cam.add_argument("--next", action="store_true",
                     help="do not ask: wait for the camera's next capture (its rate_hz; works under lockstep)")
    cam.add_argument("--timeout", type=cli_values.seconds, default=5.0)
    cam.add_argument("--url", default=None)

    mp = sub.add_parser("map", help="the occupancy map (map_server): what it holds, the state at points, "
                                    "a box's voxels, a region's free area; save, load, clear")
    mp.add_argument("action", choices=["info", "state", "box", "free-area", "save", "load", "clear"])
    mp.add_argument("args", nargs="*", help="state: X Y Z [X Y Z ...]; box and free-area: XMIN YMIN ZMIN XMAX YMAX "
                                            "ZMAX; save and load: a map's name in the server's --maps folder")
    mp.add_argument("--timeout", type=cli_values.seconds, default=5.0)
    mp.add_argument("--url", default=None)

    sc = sub.add_parser("scene", help="scene files: check one, or turn it into the world model's Turtle scene")
    sc.add_argument("action", choices=["check", "turtle"],
                    help="check: the physics server's checks (one line, or --json the normalized scene); "
                         "turtle: the world model's Turtle scene")
    sc.add_argument("scene", help="the scene file (JSON, docs/scene.md)")
    sc.add_argument("-o", "--output", default=None, help="write here instead of stdout")
    sc.add_argument("--json", action="store_true", help="check: print the normalized scene (JSON)")


def camera_main(args: argparse.Namespace) -> int:
    from skillbus.bus import open_bus
    from skillbus.perception.depth_camera import CameraError, DepthCamera
    import numpy as np
    if args.out and not args.out.endswith((".ply", ".npy")):
        print(f"error: --out {args.out}: write .ply or .npy", file=sys.stderr)
        return 2
    cam = DepthCamera(open_bus(args.url), name="skillbus-camera")
    try:
        cloud = cam.next_cloud(args.camera, args.timeout) if args.next else cam.capture(args.camera, args.timeout)
    except CameraError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    if args.out and args.out.endswith(".npy"):
        np.save(args.out, cloud.points)
    elif args.out:
        cloud.write_ply(args.out)
    print(json.dumps({"camera": cloud.camera, "capture": cloud.capture, "width": cloud.width, "height": cloud.height,
                      "returns": cloud.returns, "pose": list(cloud.pose), "out": args.out}))
    return 0


def map_main(args: argparse.Namespace) -> int:
    from skillbus.bus import open_bus
    from skillbus.perception.map_client import MapClient
    from skillbus.rpc import RpcError, RpcTimeout
    a = args.args
    try:
        nums = [float(x) for x in a] if args.action in ("state", "box", "free-area") else []
    except ValueError:
        print(f"error: map {args.action}: numbers expected, got {' '.join(a)}", file=sys.stderr)
        return 2
    if args.action == "state" and (not nums or len(nums) % 3):
        print("error: map state: give points as X Y Z [X Y Z ...]", file=sys.stderr)
        return 2
    if args.action in ("box", "free-area") and len(nums) != 6:
        print(f"error: map {args.action}: give XMIN YMIN ZMIN XMAX YMAX ZMAX", file=sys.stderr)
        return 2
    if args.action in ("save", "load") and len(a) != 1:
        print(f"error: map {args.action}: give one map name", file=sys.stderr)
        return 2
    if args.action in ("info", "clear") and a:  # (`map clear extra words` cleared the whole map)
        print(f"error: map {args.action} takes no arguments, not {' '.join(a)}", file=sys.stderr)
        return 2
    c = MapClient(open_bus(args.url), name="skillbus-map", timeout=args.timeout)
    try:
        if args.action == "state":
            pts = [nums[i:i + 3] for i in range(0, len(nums), 3)]
            out: object = [{"point": p, "state": s} for p, s in zip(pts, c.states(pts))]
        elif args.action == "box":
            out = c.box(nums[:3], nums[3:])
        elif args.action == "free-area":
            free, area = c.free_area(nums[:3], nums[3:])
            out = {"free_m2": free, "area_m2": area}
        elif args.action == "save":
            out = {"file": c.save(a[0])}
        elif args.action == "load":
            out = c.load(a[0])
        else:
            out = getattr(c, args.action)()
    except RpcTimeout as e:
        print(f"error: {e.no_answer()} (is map_server running?)", file=sys.stderr)
        return 1
    except RpcError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    print(json.dumps(out))
    return 0


def main(args: argparse.Namespace) -> int:
    if args.command == "map":
        return map_main(args)
    if args.command == "camera":
        return camera_main(args)
    if args.command == "sim-script":
        from skillbus.sim import script
        return script.main(args)
    if args.command == "scene":
        from skillbus.sim import scene
        if args.action == "turtle" and args.json:  # (it was ignored without a word)
            print("error: scene turtle --json: --json is for check (turtle prints Turtle)", file=sys.stderr)
            return 2
        try:
            if args.action == "turtle":
                text = scene.to_turtle(scene.load(args.scene))
            elif args.json:
                text = json.dumps(scene.load(args.scene), indent=1) + "\n"
            else:
                text = scene.check(args.scene) + "\n"
        except (scene.SceneError, FileNotFoundError) as e:
            print(f"error: {e}", file=sys.stderr)
            return 2
        if args.output:
            with open(args.output, "w") as f:
                f.write(text)
        else:
            sys.stdout.write(text)
        return 0
    from skillbus.bus import open_bus
    from skillbus.rpc import RpcError, RpcTimeout
    from skillbus.sim.client import SimClient
    c = SimClient(open_bus(args.url), timeout=args.timeout)
    action = args.action.replace("-", "_")
    try:
        rep = c.load_scene(args.scene) if action == "load_scene" else getattr(c, action)()
    except RpcTimeout as e:
        print(f"error: {e.no_answer()}", file=sys.stderr)
        return 1
    except RpcError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    if isinstance(rep, dict):
        print(json.dumps(rep))
    else:
        print(json.dumps({action: rep}) if args.json else rep)
    return 0
