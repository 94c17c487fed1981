"""`skillbus lockstep-session`: a lockstep session of the demo participants (no physics), the
test and benchmark of the lockstep layer alone. It runs a short
lockstep session of real processes (a C++ clock master, Python and C++ participants)
in a private network namespace and prints its summary."""

from __future__ import annotations

import json
import signal
import sys

from skillbus import paths
from skillbus.netns import Sandbox, last_json


def python_participant_argv(name: str, *extra: str) -> list[str]:
    return [sys.executable, "-m", "skillbus.cli", "lockstep-participant", "--name", name, *extra]


def run_session(box: Sandbox, frames: int, n_python: int, n_cpp: int, timeout: float,
                period_ms: float = 10.0) -> dict:
    """Runs one demo session in `box`; returns the master's summary plus the participants'."""
    names = [f"py{i + 1}" for i in range(n_python)] + [f"cpp{i + 1}" for i in range(n_cpp)]
    clock = box.start("clock", [paths.binary("sb_clock"), "--demo", "--frames", str(frames),
                                "--period-ms", str(period_ms), "--participants", ",".join(names)])
    parts = []
    for n in names:
        argv = (python_participant_argv(n) if n.startswith("py")
                else [str(paths.binary("sb_demo_participant")), "--name", n])
        parts.append(box.start(n, argv))
    box.wait(clock, timeout)
    summary = last_json(clock.stdout()) or {"ok": False, "error": f"clock printed no summary: {clock.stderr()}"}
    summary["participant_results"] = {}
    for p in parts:
        box.wait(p, 15)
        summary["participant_results"][p.name] = last_json(p.stdout()) or {"ok": False}
    return summary


def print_summary(s: dict) -> None:
    print("skillbus lockstep session")
    print(f"  result            {'ok' if s.get('ok') else 'FAILED: ' + s.get('error', '?')}")
    print(f"  participants      {s.get('participants')} ({', '.join(s.get('participant_results', {}))})")
    print(f"  frames            {s.get('frames')}")
    print(f"  sim time          {s.get('sim_time_s', 0):.3f} s")
    print(f"  wall time         {s.get('wall_time_s', 0):.3f} s")
    print(f"  real-time factor  {s.get('real_time_factor', 0):.1f}x")
    print(f"  frame overhead    {s.get('us_per_frame', 0):.0f} us/frame")
    print(f"  digest            {s.get('digest')}")
    print(f"  bad input         {s.get('bad_input')}")


class Terminated(Exception):
    """SIGTERM (a `kill`, a supervisor's stop): raised in the main thread, so that the
    sandbox's clean-up stops the session's processes. Without it the default action ended
    this process alone, and its clock and participants ran on, busy, with no one to stop
    them."""


def _terminated(signum, frame):
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # (once: the clean-up is not cut short by another)
    raise Terminated()


def main(args) -> int:
    from skillbus.netns import SandboxError
    as_json = getattr(args, "json", False)
    old = signal.signal(signal.SIGTERM, _terminated)
    try:
        with Sandbox() as box:
            print(f"running {args.frames} frames with {args.python} Python and {args.cpp} C++ participants "
                  f"({box.mode}, {box.url})", file=sys.stderr if as_json else sys.stdout, flush=True)
            s = run_session(box, args.frames, args.python, args.cpp, timeout=args.timeout)
    except SandboxError as e:  # (no private network namespace here, and no safe way without one)
        print(f"error: lockstep-session: {e}", file=sys.stderr)
        return 2
    except Terminated:
        print("lockstep-session: terminated (SIGTERM): its processes were stopped", file=sys.stderr)
        return 143
    finally:
        signal.signal(signal.SIGTERM, old)
    if as_json:
        print(json.dumps(s))
    else:
        print_summary(s)
    ok = s.get("ok") and all(p.get("ok") for p in s["participant_results"].values())
    return 0 if ok else 1
