"""Watching the bus: ``skillbus spy`` (lcm-spy with every skillbus type decodable) and
``skillbus replay LOG`` (a recorded run played back onto the bus).

lcm-spy comes with the lcm wheel; it finds message types on its class path, so spy puts
the generated types jar (build/gen/skillbus_msgs.jar) there. Both speak LCM on the
multicast group of the bus URL: to look at a recorded demo run,

    deploy/netns-run bash
    .venv/bin/skillbus spy &
    .venv/bin/skillbus replay runs/demo/demo.lcmlog
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from skillbus import paths
from skillbus.bus import resolve_url


def lcm_tool(name: str) -> str:
    return str(Path(sys.executable).parent / name)


def spy_command(url: str | None = None) -> tuple[list[str], dict[str, str]]:
    jar = paths.types_jar()
    if not jar.exists():
        raise FileNotFoundError(f"{jar} is missing: run `make build` (it generates the types jar)")
    env = dict(os.environ)
    env["CLASSPATH"] = str(jar) + (os.pathsep + env["CLASSPATH"] if env.get("CLASSPATH") else "")
    return [lcm_tool("lcm-spy"), "--lcm-url", resolve_url(url)], env


def main_spy(args) -> int:
    try:
        argv, env = spy_command(args.url)
    except FileNotFoundError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return subprocess.call(argv, env=env)


def main_replay(args) -> int:
    log = Path(args.log)
    if not log.is_file():
        print(f"error: {log}: no such log file", file=sys.stderr)
        return 2
    argv = [lcm_tool("lcm-logplayer"), "--lcm-url", resolve_url(args.url), "--speed", str(args.speed)]
    if args.channels:
        argv += ["--regexp", args.channels]
    return subprocess.call(argv + [str(log)])
