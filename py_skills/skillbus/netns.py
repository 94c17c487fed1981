"""A private network namespace for multi-process runs, and processes that never leak.

This module is public API, not a test fixture: ``skillbus lockstep-session`` and the
demo use it, as do the tests (the ``sandbox`` fixture) and the benchmarks; keep
:class:`Sandbox`, :class:`Proc`, :class:`SandboxError` and :func:`last_json` stable.
``deploy/netns-run`` is its shell twin (the same namespace set-up) for runs by hand.

LCM's UDP multicast needs a multicast route; joining a group on the host would send
IGMP reports out of the real interface. So tests and the demo run their processes in a
network namespace of their own (``unshare -rn``; loopback up, multicast on, a route for
224.0.0.0/4 to lo): hermetic, and several can run side by side. Where no namespace can
be made, :class:`Sandbox` falls back to the host only if the host already routes
multicast to lo, with ttl=0 and a port of its own; otherwise it refuses with a reason.

Example::

    with Sandbox() as box:
        clock = box.start("clock", ["build/common/sb_clock", "--participants", "p1"])
        part = box.start("p1", [sys.executable, "-m", "skillbus.cli", "lockstep-participant", "--name", "p1"])
        part.wait_for("some line", timeout=10)  # of its stderr; fails at once if it exits
        box.wait(clock, timeout=30)
    # every process is gone here, also after an exception or a timeout
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
import select
import shutil
import signal
import subprocess
import tempfile
import time
from pathlib import Path

from skillbus.waiting import wait_for_text

SETUP = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo"


def dies_with_its_starter(signal_name: str = "TERM") -> list[str]:
    """A command prefix (util-linux setpriv, after any namespace change: entering one clears
    it) that gives the program a parent-death signal: it gets `signal_name` when the thread
    that started it ends. Without it, an owner killed with SIGKILL (which no handler sees)
    left its sandbox's processes running, busy, under no one."""
    return ["setpriv", "--pdeathsig", signal_name, "--"]


class SandboxError(RuntimeError):
    pass


@dataclasses.dataclass
class Proc:
    name: str
    popen: subprocess.Popen
    stdout_path: Path
    stderr_path: Path

    @property
    def returncode(self) -> int | None:
        return self.popen.poll()

    def stdout(self) -> str:
        return self.stdout_path.read_text(errors="replace")

    def stderr(self) -> str:
        return self.stderr_path.read_text(errors="replace")

    def wait_for(self, pattern: str | re.Pattern[str], timeout: float, stream: str = "stderr",
                 what: str = "", interval: float = 0.05) -> re.Match[str]:
        """Waits until the process has written `pattern` (a string: literally; a compiled
        expression: searched) to its stderr (or stdout) and returns the match. Raises
        WaitTimeout when it has not within `timeout`, RuntimeError as soon as the process
        has ended without it; both show the end of its stderr."""
        read = self.stderr if stream == "stderr" else self.stdout
        shown = pattern.pattern if isinstance(pattern, re.Pattern) else pattern
        return wait_for_text(read, pattern, timeout, what or f"{self.name} writing {shown!r} to {stream}",
                             ended=lambda: self.returncode, interval=interval,
                             diagnostic=lambda: f"the end of {self.name}'s stderr:\n{self.stderr()[-2000:]}")


def last_json(text: str) -> dict | None:
    """The last line of a program's output that is a JSON object (its summary), or None."""
    for line in reversed(text.strip().splitlines()):
        try:
            value = json.loads(line)
        except json.JSONDecodeError:
            continue
        if isinstance(value, dict):
            return value
    return None


def _host_routes_multicast_to_lo() -> bool:
    try:
        out = subprocess.run(["ip", "route", "get", "239.255.76.67"], capture_output=True, text=True,
                             timeout=5).stdout
    except (OSError, subprocess.TimeoutExpired):
        return False
    return " dev lo " in out + " "


class Sandbox:
    """Starts processes in one private network namespace and always cleans them up."""

    def __init__(self, log_dir: str | Path | None = None, port: int | None = None, transport: str = "lcm") -> None:
        """`transport`: "lcm" (udpm://, the default) or "dds" (Cyclone DDS, dds://, on a
        domain of this sandbox's own)."""
        if transport not in ("lcm", "dds"):
            raise ValueError(f"transport {transport!r}: 'lcm' or 'dds'")
        self.transport = transport
        self._own_dir = log_dir is None
        self.log_dir = Path(log_dir or tempfile.mkdtemp(prefix="skillbus-"))
        self.log_dir.mkdir(parents=True, exist_ok=True)
        self.port = port or 7667
        self.procs: list[Proc] = []
        self._holder: subprocess.Popen | None = None
        self.mode = ""
        # Every sandbox is a deployment of its own: its processes sign and check their
        # messages with a key of its own (docs/security.md), unless $SKILLBUS_KEY_FILE says
        # otherwise ("none": an open bus).
        self._key_dir = Path(tempfile.mkdtemp(prefix="skillbus-key-"))
        self.key_file = self._key_dir / "bus.key"
        from skillbus.auth import create_key_file
        create_key_file(self.key_file)

    # -- namespace --------------------------------------------------------
    def __enter__(self) -> "Sandbox":
        try:
            self._enter_namespace()
            self.mode = "netns"
        except SandboxError as why:
            if not _host_routes_multicast_to_lo():
                # (__exit__ never runs for a sandbox that did not start: its key goes now)
                shutil.rmtree(self._key_dir, ignore_errors=True)
                if self._own_dir:
                    shutil.rmtree(self.log_dir, ignore_errors=True)
                raise SandboxError(f"no private network namespace ({why}) and the host does not route "
                                   f"multicast to lo; refusing to join multicast groups on a real "
                                   f"interface") from None
            self.mode = "host"
            self.port = 20000 + os.getpid() % 20000  # a port of our own on the shared host
        return self

    def _enter_namespace(self) -> None:
        # (the guard after unshare: entering a user namespace clears a parent-death signal)
        if not shutil.which("unshare") or not shutil.which("nsenter"):
            raise SandboxError("unshare/nsenter not found")
        self._holder = subprocess.Popen(
            ["unshare", "-rn", "--", *dies_with_its_starter("KILL"), "sh", "-c",
             f"{SETUP} && echo ready && exec sleep 2147483647"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
        ready, _, _ = select.select([self._holder.stdout], [], [], 10)
        line = self._holder.stdout.readline().decode().strip() if ready else ""
        if line != "ready":
            err = self._holder.stderr.read1(4096).decode(errors="replace").strip() if ready else "timed out"
            self._kill_holder()
            raise SandboxError(f"unshare -rn failed: {err or 'no output'}")

    def _kill_holder(self) -> None:
        if self._holder is not None:
            try:
                os.killpg(self._holder.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self._holder.wait(timeout=10)
            self._holder = None

    @property
    def url(self) -> str:
        if self.transport == "dds":
            # A domain per sandbox (within its namespace it is alone anyway; on the shared
            # host, where the port is this process's own, so is the domain).
            return f"dds://{self.port % 200 + 1}"
        return f"udpm://239.255.76.67:{self.port}?ttl=0"

    @property
    def namespace_pid(self) -> int | None:
        """A process in the namespace (for `nsenter -t`, `skillbus console --netns`); None
        when the sandbox is the host's network."""
        return self._holder.pid if self.mode == "netns" else None

    def prefix(self) -> list[str]:
        """Command prefix that runs a program inside the namespace."""
        if self.mode == "netns":
            return ["nsenter", "-t", str(self._holder.pid), "-n", "-U", "--preserve-credentials", "--"]
        return []

    def env(self, extra: dict[str, str] | None = None) -> dict[str, str]:
        e = dict(os.environ)
        e["SKILLBUS_BUS_URL"] = self.url
        e.setdefault("SKILLBUS_KEY_FILE", str(self.key_file))
        e["PYTHONUNBUFFERED"] = "1"
        extra = dict(extra or {})
        if extra.get("PYTHONPATH") and os.environ.get("PYTHONPATH"):
            # Added in front, not instead: a caller run with PYTHONPATH set (a work tree's
            # py_skills ahead of an installed skillbus) must see its processes import the same.
            extra["PYTHONPATH"] = os.pathsep.join([extra["PYTHONPATH"], os.environ["PYTHONPATH"]])
        e.update(extra)
        return e

    # -- processes --------------------------------------------------------
    def start(self, name: str, argv: list[str], env: dict[str, str] | None = None, host_network: bool = False) -> Proc:
        """Starts a process in the namespace (with host_network: in the host's network,
        for a kernel CAN interface there; it is still stopped with the sandbox). It gets
        SIGTERM when the thread that started it ends (dies_with_its_starter): start a
        sandbox's processes from a thread that lives as long as they should."""
        out = self.log_dir / f"{name}.out"
        err = self.log_dir / f"{name}.err"
        prefix = [] if host_network else self.prefix()
        with open(out, "wb") as fo, open(err, "wb") as fe:
            popen = subprocess.Popen(prefix + dies_with_its_starter() + [str(a) for a in argv], stdout=fo, stderr=fe,
                                     stdin=subprocess.DEVNULL, env=self.env(env), start_new_session=True)
        proc = Proc(name, popen, out, err)
        self.procs.append(proc)
        return proc

    def wait(self, proc: Proc, timeout: float) -> int:
        """Waits for one process; raises TimeoutError naming it (the sandbox still cleans up)."""
        try:
            return proc.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise TimeoutError(f"{proc.name} did not finish within {timeout:.0f} s; "
                               f"last stderr: {proc.stderr()[-2000:]}") from None

    def wait_all(self, timeout: float) -> dict[str, int]:
        deadline = time.monotonic() + timeout
        return {p.name: self.wait(p, max(0.0, deadline - time.monotonic())) for p in self.procs}

    def kill(self, proc: Proc, sig: int = signal.SIGKILL) -> None:
        try:
            os.killpg(proc.popen.pid, sig)
        except ProcessLookupError:
            pass

    def stop_all(self, grace: float = 3.0) -> None:
        for p in self.procs:
            if p.popen.poll() is None:
                self.kill(p, signal.SIGTERM)
        deadline = time.monotonic() + grace
        for p in self.procs:
            try:
                p.popen.wait(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                self.kill(p, signal.SIGKILL)
                p.popen.wait(timeout=10)

    def __exit__(self, *exc) -> None:
        try:
            self.stop_all()
        finally:
            self._kill_holder()
            shutil.rmtree(self._key_dir, ignore_errors=True)
            if self._own_dir and exc[0] is None:
                shutil.rmtree(self.log_dir, ignore_errors=True)
