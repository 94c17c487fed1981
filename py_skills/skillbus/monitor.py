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
import time
from pathlib import Path

from skillbus import paths
from skillbus.bus import channel, open_bus, resolve_url
from skillbus.waiting import wait_until

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


LOG_MARK_CHANNEL = "SB_LOG_MARK"  # (not a channel any program listens to)


def mark_log(log: str | Path, timeout: float = 10.0, url: str | None = None) -> str:
    """Waits until the recorder (skillbus record, lcm-logger), writing `log`, has recorded a marker published now: from
    then on it records everything, and everything that reached it before the marker is
    in the file. Call it after starting the logger (before what must be recorded) and
    before stopping it (instead of a pause "for the last messages"). The marker is a
    test_sample_t with a unique text on SB_LOG_MARK, published every 50 ms until the
    logger has written one (it flushes every 100 ms); it decodes like every message of
    a run. Returns the marker's text; WaitTimeout when the log has none within `timeout`."""
    from skillbus.msgs import test_sample_t
    log = Path(log)
    token = f"skillbus-log-mark:{os.getpid()}:{time.monotonic_ns()}"
    m = test_sample_t()
    m.text, m.blob = token, bytes(4)
    data, needle = m.encode(), token.encode()
    try:
        start = log.stat().st_size  # (only what is written from now on can hold it)
    except FileNotFoundError:
        start = 0
    bus = open_bus(url)

    def logged() -> bool:
        bus.publish(channel(LOG_MARK_CHANNEL), data)
        try:
            with open(log, "rb") as f:
                f.seek(start)
                return needle in f.read()
        except FileNotFoundError:
            return False

    wait_until(logged, timeout, f"a marker in the LCM log {log} (is a recorder, skillbus record, writing it, on this bus?)")
    return token


def lcm_tool(name: str) -> str:
    return str(Path(sys.executable).parent / name)


def spy_command(url: str | None = None) -> tuple[list[str], dict[str, str]]:
    """lcm-spy's command line; BusError where the bus would be joined on a network card
    (LCM's tools have no guard of their own: skillbus checks for them, as open_bus does)."""
    from skillbus.bus import check_multicast_interface
    check_multicast_interface(resolve_url(url))
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
    from skillbus.bus import BusError
    try:
        argv, env = spy_command(args.url)
    except (FileNotFoundError, BusError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return run_foreground(argv, env=env)


def regex_error(pattern: str) -> str:
    """Why `pattern` is no regular expression, or "" (LCM compiles subscriptions with GLib's
    regular expressions, PCRE's syntax, as Python's `re` nearly is).

    >>> regex_error("SB_SIM_.*"), regex_error("[")
    ('', 'unterminated character set at position 0')
    """
    import re
    try:
        re.compile(pattern)
    except re.error as e:
        return str(e)
    return ""


def main_replay(args) -> int:
    log = Path(args.log)
    if not log.is_file():
        print(f"error: {log}: no such log file", file=sys.stderr)
        return 2
    from skillbus.bus import BusError, check_multicast_interface
    try:
        check_multicast_interface(resolve_url(args.url))  # (lcm-logplayer has no guard of its own)
    except BusError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    argv = [lcm_tool("lcm-logplayer"), "--lcm-url", resolve_url(args.url), "--speed", str(args.speed)]
    if args.channels:
        # lcm-logplayer takes a regular expression it cannot compile as matching nothing: it
        # printed a line, played nothing for the log's length and exited 0.
        why = regex_error(args.channels)
        if why:
            print(f"error: replay --channels {args.channels!r}: not a regular expression ({why})", file=sys.stderr)
            return 2
        argv += ["--regexp", args.channels]
    return run_foreground(argv + [str(log)])
