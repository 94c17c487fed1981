"""`skillbus console [--port 8080] [--host 127.0.0.1]`."""

from __future__ import annotations

import argparse
import logging
import sys

from skillbus import cli_values


def add_parser(sub) -> None:
    c = sub.add_parser("console", help="the web console: skills, tasks, world model (docs/console.md)")
    c.add_argument("--port", type=cli_values.port, default=8080, help="HTTP port (default 8080; 0: any free port)")
    c.add_argument("--host", default="127.0.0.1",
                   help="the address to serve on (default: this machine only; 0.0.0.0 serves every network the "
                        "machine is on, to anyone who reaches it: the console starts and stops tasks)")
    c.add_argument("--url", default=None, help="the bus (default: $SKILLBUS_BUS_URL)")
    c.add_argument("--scene", default=None, metavar="FILE.scene.json",
                   help="the scene the 3D view draws (default: the demo's)")
    c.add_argument("--token", default=None, help="the token the API asks for (default: $SKILLBUS_CONSOLE_TOKEN, else a "
                                                 "new one each run, in the URL it prints; an argument is visible to "
                                                 "every user in the process list: prefer the variable)")
    c.add_argument("--no-token", action="store_true",
                   help="no token: anyone who reaches the port commands the robot (behind an authenticating proxy)")
    c.add_argument("--log", default=None, metavar="FILE.lcmlog",
                   help="open this recorded run for replay at once (the Replay page opens others)")
    c.add_argument("--netns", type=int, default=None, metavar="PID",
                   help="hear the bus in the network namespace of process PID (a system under deploy/netns-run or "
                        "skillbus demo) while serving the page in this one, where the browser is")
    c.add_argument("--listen-fd", type=int, default=None, help=argparse.SUPPRESS)  # (--netns: the socket, inherited)
    # test: lose every N-th progress message it hears (the catch-up from SKILL.tasks must
    # still give every task its final tree)
    c.add_argument("--lose-progress-every", type=int, default=0, help=argparse.SUPPRESS)


def main(args: argparse.Namespace) -> int:
    import os
    # An empty --host (an unset $HOST in a script) served every network the machine is on;
    # and a token given with --no-token was dropped without a word.
    if not args.host.strip():
        print("error: console --host: empty (give an address: 127.0.0.1 for this machine only, 0.0.0.0 for every "
              "network)", file=sys.stderr)
        return 2
    if args.no_token and args.token is not None:
        print("error: console: --token and --no-token: one or the other", file=sys.stderr)
        return 2
    import socket

    import uvicorn

    from skillbus.bus import open_bus
    from skillbus.console.server import create_app
    from skillbus.monitor import watch_url

    def bus():
        b = open_bus(watch_url(args.url))
        if args.lose_progress_every > 0:
            from skillbus.bus import DropEveryNthReceivedBus
            b = DropEveryNthReceivedBus(b, args.lose_progress_every, ("SB_SKILL_PROGRESS",))
        return b

    if args.listen_fd is not None:
        sock = socket.socket(fileno=args.listen_fd)
    else:
        # The socket is bound here, so a port in use is one line, and --port 0's port is known.
        try:
            sock = socket.create_server((args.host, args.port))
        except OSError as e:
            print(f"error: cannot serve on {args.host}:{args.port}: {e.strerror or e}", file=sys.stderr)
            return 1
    if args.netns is not None:
        from skillbus.console import access
        return _serve_from_namespace(args, sock, None if args.no_token else
                                     (args.token or os.environ.get(access.TOKEN_ENV) or access.new_token()))
    from pathlib import Path
    from skillbus.console.live import ConsoleError
    try:
        from skillbus.console import access
        token = None if args.no_token else (args.token or os.environ.get(access.TOKEN_ENV) or access.new_token())
        app = create_app(bus, Path(args.scene) if args.scene else None, Path(args.log) if args.log else None, token)
    except (ConsoleError, OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    host, port = sock.getsockname()[:2]
    print(f"skillbus console: http://{host}:{port}/" + (f"?token={token}" if token else ""), flush=True)
    logging.getLogger("uvicorn.error").setLevel(logging.WARNING)
    # (open live pages would hold a graceful shutdown for ever: they get 2 s)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", lifespan="on", timeout_graceful_shutdown=2,
                                          ws_per_message_deflate=False))  # (loopback: compressing costs, saves nothing)
    server.run(sockets=[sock])
    return 0


def _serve_from_namespace(args: argparse.Namespace, sock, token: str | None) -> int:
    """--netns PID: the listening socket stays in this network namespace (a socket belongs
    to the namespace it was made in), the console itself runs in PID's, where the bus is:
    nsenter into it (a user namespace of our own: no privileges needed), the socket
    inherited, the same arguments otherwise."""
    import os
    import shutil

    from skillbus.console import access
    if not os.path.exists(f"/proc/{args.netns}/ns/net"):
        print(f"error: --netns {args.netns}: no such process", file=sys.stderr)
        return 1
    nsenter = shutil.which("nsenter")
    if nsenter is None:
        print("error: --netns needs nsenter (util-linux)", file=sys.stderr)
        return 1
    os.set_inheritable(sock.fileno(), True)
    argv = [a for a in sys.argv[1:]]
    i = argv.index("--netns") if "--netns" in argv else -1
    argv = argv[:i] + argv[i + 2:] if i >= 0 else [a for a in argv if not a.startswith("--netns=")]
    argv += ["--listen-fd", str(sock.fileno())]
    if token:  # (in the environment, which only this user reads; not in the arguments, which all users see)
        os.environ[access.TOKEN_ENV] = token
    host, port = sock.getsockname()[:2]
    sys.stderr.write(f"serving http://{host}:{port}/ here, hearing the bus of process {args.netns}'s network\n")
    # Into its user namespace too when it has one of its own (netns-run's, the tests'), as
    # the one that may enter its network namespace without privileges.
    own_user_ns = os.readlink(f"/proc/{args.netns}/ns/user") != os.readlink("/proc/self/ns/user")
    cmd = [nsenter, "-t", str(args.netns), "-n", *(["-U", "--preserve-credentials"] if own_user_ns else []), "--",
           sys.executable, "-m", "skillbus.cli", *argv]
    os.execv(nsenter, cmd)
    return 1  # (not reached)
