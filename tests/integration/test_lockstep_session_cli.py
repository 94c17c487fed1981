"""`skillbus lockstep-session` stopped with SIGTERM stops its session's processes too: before,
the default action ended it alone, and its clock master and participants ran on, busy,
under no one (a test's timeout or a `kill` left them for good)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time


def descendants(pid: int) -> set[int]:
    children: dict[int, list[int]] = {}
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                ppid = int(open(f"/proc/{d}/stat").read().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(d))
    out, todo = set(), [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            out.add(c)
            todo.append(c)
    return out


def alive(pid: int) -> bool:
    try:
        return open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_sigterm_stops_the_sessions_processes_too():
    p = subprocess.Popen([sys.executable, "-m", "skillbus.cli", "lockstep-session", "--frames", "100000000",
                          "--python", "1", "--cpp", "1", "--timeout", "600"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    kids: set[int] = set()
    try:
        assert p.stdout.readline().startswith("running 100000000 frames"), p.stderr.read()
        deadline = time.monotonic() + 30
        while len(kids := {k for k in descendants(p.pid) if alive(k)}) < 3:  # the clock and two participants (at least)
            assert time.monotonic() < deadline, kids
            time.sleep(0.1)
        p.send_signal(signal.SIGTERM)
        assert p.wait(30) == 143, p.stderr.read()
        deadline = time.monotonic() + 10
        while left := {k for k in kids if alive(k)}:
            assert time.monotonic() < deadline, {k: open(f"/proc/{k}/cmdline").read() for k in left if alive(k)}
            time.sleep(0.1)
    finally:
        if p.poll() is None:
            p.kill()
        for k in kids | descendants(p.pid):  # (whatever was left, even reparented)
            try:
                os.kill(k, signal.SIGKILL)
            except ProcessLookupError:
                pass
