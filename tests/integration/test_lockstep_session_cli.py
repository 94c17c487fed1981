"""`skillbus lockstep-session` stopped with SIGTERM stops its session's processes too: before,
the default action ended it alone, and its clock master and participants ran on, busy,
under no one (a test's timeout or a `kill` left them for good). Killed (SIGKILL, which no
handler sees), its processes end too: every process a sandbox starts has a parent-death
signal (skillbus.netns.dies_with_its_starter)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest


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


def cmdline(pid: int) -> str:
    try:
        return open(f"/proc/{pid}/cmdline").read().replace("\0", " ")
    except OSError:
        return ""


def alive(pid: int) -> bool:
    try:
        return open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.parametrize("sig,code", [(signal.SIGTERM, 143), (signal.SIGKILL, -9)], ids=["SIGTERM", "SIGKILL"])
def test_a_stopped_or_killed_session_takes_its_processes_with_it(sig, code):
    p = subprocess.Popen([sys.executable, "-m", "skillbus.cli", "lockstep-session", "--frames", "100000000",
                          "--python", "1", "--cpp", "1", "--timeout", "600"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    kids: set[int] = set()
    try:
        assert p.stdout.readline().startswith("running 100000000 frames"), p.stderr.read()
        deadline = time.monotonic() + 30
        programs = ("sb_clock", "lockstep-participant", "sb_demo_participant")
        # (the programs themselves running, the clock and two participants, not their launchers)
        while True:
            kids = {k for k in descendants(p.pid) if alive(k)}
            if all(any(x in cmdline(k) for k in kids) for x in programs):
                break
            assert time.monotonic() < deadline, {k: cmdline(k) for k in kids}
            time.sleep(0.1)
        p.send_signal(sig)
        assert p.wait(30) == code, p.stderr.read()
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
