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
import signal
import subprocess
import sys
from pathlib import Path

from skillbus import paths
from skillbus.bus import resolve_url

WATCH_RECV_BUF = 8 << 20  # bytes of socket receive buffer a watcher asks for (the kernel's cap applies)


def watch_url(url: str | None = None) -> str:
    """The bus URL for a process that watches the bus (the demo's live view, `skillbus run
    --watch`): with udpm://, a large socket receive buffer. Every process on the multicast
    group receives every datagram of its lane; with the kernel's default buffer (about
    200 KB, under 100 ms of a lockstep run at several times real time) a watcher that is
    not scheduled for a moment loses messages. Asks for at most net.core.rmem_max, so that
    LCM has no reason to warn."""
    url = resolve_url(url)
    if not url.startswith("udpm://") or "recv_buf_size=" in url:
        return url
    try:
        cap = int(Path("/proc/sys/net/core/rmem_max").read_text())
    except (OSError, ValueError):
        return url
    size = min(WATCH_RECV_BUF, cap)
    return url + ("&" if "?" in url else "?") + f"recv_buf_size={size}"


def lcm_tool(name: str) -> str:
    return str(Path(sys.executable).parent / name)


def spy_command(url: str | None = None) -> tuple[list[str], dict[str, str]]:
    jar = paths.types_jar()
    if not jar.exists():
        raise FileNotFoundError(f"{jar} is missing: run `make build` (it generates the types jar)")
    env = dict(os.environ)
    env["CLASSPATH"] = str(jar) + (os.pathsep + env["CLASSPATH"] if env.get("CLASSPATH") else "")
    return [lcm_tool("lcm-spy"), "--lcm-url", resolve_url(url)], env


def run_foreground(argv: list[str], env: dict[str, str] | None = None) -> int:
    """Runs a program in the foreground and returns its exit code. Ctrl-C reaches it from
    the terminal (same process group) and it ends in its own way: this process waits for
    that, without a traceback (subprocess.call would SIGKILL it, which leaves whatever it
    started behind: the demo's supervisord). SIGTERM is passed on to it."""
    child = subprocess.Popen(argv, env=env)

    def on_signal(signum, frame):
        if signum == signal.SIGTERM and child.poll() is None:
            child.send_signal(signum)

    old = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        rc = child.wait()
    finally:
        for sig, h in old.items():
            signal.signal(sig, h)
    return 128 - rc if rc < 0 else rc  # (killed by a signal: 128 + its number, as a shell says)


def main_spy(args) -> int:
    try:
        argv, env = spy_command(args.url)
    except FileNotFoundError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return run_foreground(argv, env=env)


def main_replay(args) -> int:
    log = Path(args.log)
    if not log.is_file():
        print(f"error: {log}: no such log file", file=sys.stderr)
        return 2
    argv = [lcm_tool("lcm-logplayer"), "--lcm-url", resolve_url(args.url), "--speed", str(args.speed)]
    if args.channels:
        argv += ["--regexp", args.channels]
    return run_foreground(argv + [str(log)])
