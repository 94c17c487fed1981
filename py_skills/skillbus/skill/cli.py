"""`skillbus skills`, `skillbus run`, `skillbus stop`, `skillbus skills-process`."""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import sys
import time
from typing import Any

from skillbus.bus import BusError, channel, open_bus
from skillbus.msgs import (decode, skill_list_t, skill_param_t, skill_progress_list_t, skill_progress_t, skill_start_t,
                           skill_task_t,
                           skill_value_t)
from skillbus.rpc import RpcClient, RpcError, RpcRemoteError, RpcTimeout, no_answer
from skillbus.skill.params import ParamTypes
from skillbus.skill.skill import State
from skillbus.waiting import poll_until
from skillbus.world.element import Element
from skillbus import cli_values

# Names of the IDL's numbers (skill_state_t, skill_param_t), for printing.
STATES = {int(s): s.name for s in State}
PARAM_TYPES = {int(t): t.name for t in ParamTypes}

MANAGER_TIMEOUT = 2.0   # s: how long a command waits for the skill manager's answer
STOP_ACK_TIMEOUT = 2.0  # s: for the acknowledgement of the stop of an interrupted run
FINAL_TIMEOUT = 5.0     # s: then for the task's final progress (the manager preempts at its next tick)
CATCH_UP_S = 1.0        # s: without progress of a task this long, ask its manager for its tree (SKILL.tasks)
EXIT_TIMEOUT = 3


class NoManager(RuntimeError):
    """No skill manager answered: one line for the user instead of a traceback."""

    def __init__(self, timeout: float) -> None:
        super().__init__(no_answer("SKILL", timeout))


class Interrupts:
    """SIGINT and SIGTERM set a flag instead of raising (KeyboardInterrupt in the middle of
    LCM's dispatch loses the task and the traceback); the loops look at it. Exit code
    128 + the signal (130, 143)."""

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.signum: int | None = None
        self.count = 0
        self._old: dict[int, object] = {}

    def _on_signal(self, signum, frame) -> None:
        self.signum = signum if self.signum is None else self.signum
        self.count += 1

    def __enter__(self) -> "Interrupts":
        for s in self.SIGNALS:
            self._old[s] = signal.signal(s, self._on_signal)
        return self

    def __exit__(self, *exc) -> None:
        for s, h in self._old.items():
            signal.signal(s, h)

    @property
    def exit_code(self) -> int:
        return 128 + (self.signum or 0)

    @property
    def name(self) -> str:
        return signal.Signals(self.signum).name if self.signum else ""

    @contextlib.contextmanager
    def held(self):
        """Signals wait (blocked) while an RPC is in flight, at most its timeout: a start
        interrupted halfway would leave a task whose id we never learn. They are handled
        (the flag set) when the block ends."""
        old = signal.pthread_sigmask(signal.SIG_BLOCK, self.SIGNALS)
        try:
            yield
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)  # runs the handlers of held signals

    def handle(self, bus, timeout: float) -> None:
        """bus.handle(timeout), ended early by a signal. LCM's select fails with EINTR when a
        signal arrives and lcm_handle_timeout() returns -1 (the bus raises BusError, the lcm
        module OSError): with the flag set that is an interruption, not an error."""
        seen = self.count
        try:
            bus.handle(timeout)
        except (BusError, OSError):
            if not self._arrived(seen):
                raise

    def _arrived(self, seen: int) -> bool:
        # The Python-level handler runs at the next check of the interpreter (at the latest
        # once the signal mask is read back here); look again after it.
        signal.pthread_sigmask(signal.SIG_BLOCK, [])
        return self.count > seen


def call(client: RpcClient, method: str, req, reply_type, intr: Interrupts | None = None,
         timeout: float = MANAGER_TIMEOUT):
    """One call to the skill manager; NoManager when it does not answer."""
    with intr.held() if intr else contextlib.nullcontext():
        try:
            return client.call(method, req, reply_type, timeout=timeout)
        except RpcTimeout:
            raise NoManager(timeout) from None


ROBOT_HELP = ("the robot whose skill manager to use (its channels are NAME/SB_SKILL_...; default: "
              "$SKILLBUS_ROBOT, else the manager without a robot name)")


def add_parsers(sub) -> None:
    sp = sub.add_parser("skills-process", help="load skill libraries and serve them to a skill manager")
    sp.add_argument("--name", default=None, help="unique name of this process")
    sp.add_argument("--robot", default=None, metavar="NAME",
                    help="the robot it serves: its manager, arm, camera and gripper channels are NAME/SB_...")
    sp.add_argument("--library", action="append", default=None, help="a Python module of skills (repeatable)")
    sp.add_argument("--config", default=None, metavar="FILE.toml",
                    help="settings and [interfaces] from a file (docs/skills.md, 'Robot interfaces')")
    sp.add_argument("--interface", action="append", default=None, metavar="NAME=MODULE[:ARG]",
                    help="a robot interface for the skills, e.g. arm=skillbus.robot.arm (repeatable)")
    sp.add_argument("--url", default=None)
    sp.add_argument("--register-timeout", type=cli_values.seconds, default=30.0)
    sp.add_argument("--standalone", action="store_true",
                    help="serve ticks without a skill manager: no registration, no heartbeat (for a "
                         "program that ticks the process itself, e.g. bench/tick_rtt_bench)")
    sp.add_argument("--lockstep", action="store_true", help="be a lockstep participant named --name")
    sp.add_argument("--gripper", default=None, metavar="CHANNEL[:NODE]",
                    help="shortcut for --interface gripper=skillbus.can.gripper_service:CHANNEL[:NODE]")
    sp.add_argument("--can-interface", default="skillbus_vcan", help="python-can interface of --gripper")
    sp.add_argument("--arm", action="store_true",
                    help="shortcut for --interface arm=skillbus.robot.arm (robot state, trajectories, motion service)")
    sp.add_argument("--world-model", action="store_true", help="give skills a world-model client (self.wmi)")
    ls = sub.add_parser("skills", help="the skills the managers know, with parameters and conditions (every "
                                       "robot's, or --robot NAME's)")
    ls.add_argument("--url", default=None)
    ls.add_argument("--robot", default=None, metavar="NAME",
                    help="only this robot's manager (default: every manager that answers on the bus)")
    ls.add_argument("--json", action="store_true",
                    help="print a JSON list: each skill with its parameters (kind, type, defaults) and conditions")
    run = sub.add_parser("run", help="run a skill; exit 0 on success; interrupted (130, 143) or timed out (3): "
                                     "the task is stopped")
    run.add_argument("skill", help="skill type (or implementation label with --label)")
    run.add_argument("--label", default="")
    run.add_argument("-p", "--param", action="append", default=[], metavar="KEY=VALUE")
    run.add_argument("--watch", action="store_true", help="show the live tree while it runs")
    run.add_argument("-v", "--verbose", action="store_true", help="show each primitive's parameters")
    run.add_argument("--timeout", type=cli_values.seconds_or_never, default=0.0,
                     help="stop the task after this many seconds and exit 3 (0: never)")
    run.add_argument("--detach", action="store_true",
                     help="print the task id and return at once, leaving the task running (skillbus stop ID)")
    run.add_argument("--json", action="store_true",
                     help="print the result and the final tree as one JSON object (with --watch, each tree "
                          "shown before it as a JSON line)")
    run.add_argument("--url", default=None)
    run.add_argument("--robot", default=None, metavar="NAME", help=ROBOT_HELP)
    wa = sub.add_parser("watch", help="follow a running task to its end, printing what changes (a task started "
                                      "elsewhere too); exit as run's; an interrupt leaves the task running")
    wa.add_argument("task", type=int)
    wa.add_argument("-v", "--verbose", action="store_true", help="show each primitive's parameters")
    wa.add_argument("--timeout", type=cli_values.seconds_or_never, default=0.0, help="stop watching after this many seconds, exit 3 (0: never)")
    wa.add_argument("--json", action="store_true", help="each tree shown as a JSON line, then the result")
    wa.add_argument("--url", default=None)
    wa.add_argument("--robot", default=None, metavar="NAME", help=ROBOT_HELP)
    for verb, text in (("stop", "preempt a running task"), ("pause", "stop ticking a task"),
                       ("resume", "tick a paused task again"), ("step", "tick a paused task once")):
        st = sub.add_parser(verb, help=text)
        st.add_argument("task", type=int)
        st.add_argument("--url", default=None)
        st.add_argument("--robot", default=None, metavar="NAME", help=ROBOT_HELP)


def skill_list(client: RpcClient) -> skill_list_t:
    return client.call("list", skill_start_t(), skill_list_t)


def print_skills(lst: skill_list_t) -> None:
    for d, proc in sorted(zip(lst.skills, lst.processes), key=lambda x: (x[0].type, x[0].label)):
        kind = "compound" if d.compound else "primitive"
        print(f"{d.type} ({d.label}, {kind}, process {proc})")
        for p in d.params:
            dt = p.data_type + (f" {p.concept}" if p.concept else "")
            default = ", ".join(_text(v) for v in p.defaults)
            print(f"    {p.key}: {dt}, {PARAM_TYPES.get(p.param_type, '?')}" + (f", = {default}" if default else "")
                  + (f"  -- {p.description}" if p.description else ""))
        for name, conds in (("pre", d.pre), ("hold", d.hold), ("post", d.post)):
            for c in conds:
                neg = "" if c.desired_state else "not "
                print(f"    {name}: {c.label}: {neg}{c.kind} {c.owl} {c.subject} {c.object}".rstrip())


def _text(v) -> str:
    from skillbus.skill.convert import value_from_msg
    x = value_from_msg(v)
    return (x.id or x.type) if isinstance(x, Element) else str(x)


def value_json(v) -> Any:
    """A skill_value_t as JSON: its value; an element as {id, type, label}."""
    from skillbus.skill.convert import value_from_msg
    x = value_from_msg(v)
    return {"id": x.id, "type": x.type, "label": x.label} if isinstance(x, Element) else x


def condition_json(c) -> dict[str, Any]:
    return {"kind": c.kind, "label": c.label, "subject": c.subject, "object": c.object, "owl": c.owl,
            "desired_state": bool(c.desired_state), "op": c.op,
            "value": value_json(c.value) if c.kind == "Property" else None, "or_label": c.or_label}


def skill_json(d, process: str) -> dict[str, Any]:
    """One skill of the manager's list as `skillbus skills --json` prints it."""
    return {"type": d.type, "label": d.label, "compound": bool(d.compound), "process": process,
            "params": [{"key": p.key, "kind": PARAM_TYPES.get(p.param_type, "?"), "data_type": p.data_type,
                        "concept": p.concept, "defaults": [value_json(v) for v in p.defaults],
                        "options": list(p.options), "description": p.description} for p in d.params],
            "pre": [condition_json(c) for c in d.pre], "hold": [condition_json(c) for c in d.hold],
            "post": [condition_json(c) for c in d.post]}


def skills_json(lst: skill_list_t) -> list[dict[str, Any]]:
    return [skill_json(d, p) for d, p in sorted(zip(lst.skills, lst.processes), key=lambda x: (x[0].type, x[0].label))]


def progress_json(p: skill_progress_t) -> dict[str, Any]:
    """A task's progress (its whole tree) as JSON; each node's parameters as a dict."""
    return {"task": p.task, "tick": p.tick, "state": STATES.get(p.state, "?"), "sim_time_s": p.header.sim_time_ns * 1e-9,
            "nodes": [{"id": n.id, "parent": n.parent, "type": n.type, "label": n.label, "processor": n.processor,
                       "state": STATES.get(n.state, "?"), "message": n.message, "code": n.code,
                       "progress": n.progress if math.isfinite(n.progress) else None,  # (JSON has no NaN)
                       "params": dict(line.split("=", 1) for line in n.params.splitlines() if "=" in line)}
                      for n in p.nodes]}


def parse_param(text: str, lst: skill_list_t | None = None, skill: str = "") -> skill_param_t:
    """`-p KEY=VALUE` as text: the skill manager types it by the skill's description and
    refuses a key or value that does not fit (one parser for every client:
    skill_mgr/src/param_check.cpp; `lst` and `skill` are no longer needed)."""
    if "=" not in text:
        raise ValueError(f"-p {text!r}: expected KEY=VALUE")
    key, raw = text.split("=", 1)
    v = skill_value_t()
    v.type, v.s = skill_value_t.STRING, raw
    m = skill_param_t()
    m.key, m.data_type = key, ""  # no data type: text for the manager to parse
    m.values, m.num_values = [v], 1
    return m


def node_line(n, name: str) -> str:
    """One node as the terminal shows it: its name, state, message (and an error's code)."""
    proc = f" [{n.processor}]" if n.processor and n.type else ""
    msg = f": {n.message}" if n.message else ""
    # A negative code is an error's; a positive one is the progress counter (SkiROS2's:
    # each step and success adds one), shown by --json only.
    return f"{name}{proc} {STATES.get(n.state, '?')}{msg}" + (f" (code {n.code})" if n.code < 0 else "")


def print_tree(p: skill_progress_t, verbose: bool = False) -> None:
    depth: dict[int, int] = {}
    for n in p.nodes:
        d = 0 if n.parent < 0 else depth[n.parent] + 1
        depth[n.id] = d
        print("  " * d + node_line(n, n.type or f"({n.processor})"))
        if verbose and n.params:
            for line in n.params.strip().splitlines():
                print(f"{'  ' * (d + 2)}{line}")


class ChangePrinter:
    """`skillbus run --watch` and `skillbus watch`: after each progress, only the nodes
    whose state, message (or, verbose, parameters) changed, each named by its path
    ('ClearTable / PickAndPlace / Grasp Running: closing'), under '--- task N, tick T'."""

    def __init__(self, verbose: bool = False) -> None:
        self.verbose = verbose
        self.shown: dict[int, tuple] = {}

    def print(self, p: skill_progress_t) -> None:
        from skillbus.skill.task_tree import node_path
        dicts = [{"type": n.type, "processor": n.processor, "parent": n.parent} for n in p.nodes]
        lines = []
        for n in p.nodes:
            key = (n.type, n.parent, n.state, n.message, n.code < 0) + ((n.params,) if self.verbose else ())
            if self.shown.get(n.id) == key:
                continue
            self.shown[n.id] = key
            lines.append(node_line(n, node_path(dicts, n.id)))
            if self.verbose and n.params:
                lines += [f"    {line}" for line in n.params.strip().splitlines()]
        for i in [i for i in self.shown if i >= len(p.nodes)]:  # a tree that shrank (a re-expansion)
            del self.shown[i]
        if lines:
            print(f"--- task {p.task}, tick {p.tick}")
            print("\n".join(lines), flush=True)


def run(args) -> int:
    if args.detach and (args.watch or args.timeout > 0):
        print("error: --detach returns at once: it takes neither --watch nor --timeout", file=sys.stderr)
        return 2
    return _with_manager(_run, args)


def _with_manager(command, args) -> int:
    """Runs `command(args, intr)` with signals held as flags; a manager that does not
    answer is one line (exit 1, or the signal's code if one came meanwhile)."""
    with Interrupts() as intr:
        try:
            return command(args, intr)
        except NoManager as e:
            print(f"error: {e}{_other_managers(args)}", file=sys.stderr)
            return intr.exit_code if intr.signum else 1


def _other_managers(args) -> str:
    """When the manager asked for does not answer: which robots' managers do ("" if none)."""
    from skillbus.channels import current_robot
    from skillbus.skill.managers import discover, robots_text
    try:
        found = [m for m in discover(open_bus(args.url)) if m.robot != current_robot()]
    except (BusError, OSError):  # (only a hint: the error above stands either way)
        return ""
    if not found:
        return ""
    return f"; the skill managers on this bus are those of the robots {robots_text(found)}: name one with --robot NAME"


class ManagerWatch:
    """Whether the skill manager that runs our task is still the one that started it.

    The manager announces itself on SB_SKILL_MANAGER every second on the wall clock
    (skill_alive_t, with an incarnation that changes when it restarts). A task lives in
    the manager's memory: a manager that restarted has lost it, and one that went silent
    (killed, hung) will never report its end. Either is said at once rather than after
    the run's --timeout. The start's reply names the manager's incarnation; under
    lockstep the manager does not announce itself (the clock master names a dead
    participant) and the reply says 0: nothing is judged before a first announcement."""

    SILENT_S = 3.5  # three missed announcements and a half

    def __init__(self, bus) -> None:
        import time
        self._time = time.monotonic
        self.incarnation: int | None = None
        self.last_seen = 0.0
        self.restarted_as: int | None = None
        bus.subscribe(channel("SB_SKILL_MANAGER"), self._on_alive)

    def started(self, task: skill_task_t) -> None:
        """The manager that accepted the task: its incarnation (0: it does not announce
        itself) counts as seen now."""
        if task.manager_incarnation and self.incarnation is None:
            self.incarnation = task.manager_incarnation
            self.last_seen = self._time()

    def _on_alive(self, ch, data) -> None:
        from skillbus.msgs import skill_alive_t
        a = decode(skill_alive_t, data)
        if a is None:
            return
        if self.incarnation is None:
            self.incarnation = a.incarnation
        elif a.incarnation != self.incarnation and self.restarted_as is None:
            self.restarted_as = a.incarnation
        self.last_seen = self._time()

    def lost(self, task: int) -> str:
        """Why the task is lost, or ""."""
        if self.restarted_as is not None:
            return (f"the skill manager restarted while task {task} ran (incarnation {self.incarnation} -> "
                    f"{self.restarted_as}): the task was lost with it")
        if self.incarnation is not None and self._time() - self.last_seen > self.SILENT_S:
            return (f"the skill manager went silent: no announcement on SB_SKILL_MANAGER for {self.SILENT_S} s "
                    f"(killed or hung?); task {task}'s end is unknown")
        return ""


def unknown_skill(name: str, lst: skill_list_t) -> str:
    """Why `name` is no skill of the manager's list, with what it has: none at all is said as
    such (right after `skillbus launch` the skill processes may not have registered yet).

    >>> unknown_skill("Pick", skill_list_t())
    "unknown skill 'Pick': the skill manager has no skills yet (no skill process has registered with it: still starting, or not running? `skillbus skills` lists them)"
    """
    have = sorted({d.type for d in lst.skills})
    if not have:
        return (f"unknown skill {name!r}: the skill manager has no skills yet (no skill process has registered with "
                f"it: still starting, or not running? `skillbus skills` lists them)")
    return f"unknown skill {name!r} (available: {', '.join(have)})"


def _run(args, intr: Interrupts) -> int:
    from skillbus.monitor import watch_url
    bus = open_bus(watch_url(args.url))  # (a large receive buffer: progress is not lost while it prints)
    client = RpcClient(bus, "SKILL", "cli")
    lst = call(client, "list", skill_start_t(), skill_list_t, intr)
    if intr.signum:
        return intr.exit_code
    req = skill_start_t()
    known = {d.type for d in lst.skills} | {d.label for d in lst.skills}
    if args.skill not in known:
        print(f"error: {unknown_skill(args.skill, lst)}", file=sys.stderr)
        return 2
    by_label = next((d for d in lst.skills if d.label == args.skill and d.type != args.skill), None)
    if by_label and args.label and args.label != by_label.label:  # (it was ignored: the label ran)
        print(f"error: {args.skill!r} is the label of an implementation of {by_label.type}, and --label "
              f"{args.label!r} names another: give the type ({by_label.type} --label {args.label}) or one label",
              file=sys.stderr)
        return 2
    req.type, req.label = (by_label.type, by_label.label) if by_label else (args.skill, args.label)
    try:
        req.params = [parse_param(p, lst, args.skill) for p in args.param]
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    req.num_params = len(req.params)
    as_json = getattr(args, "json", False)
    say = sys.stderr if as_json else sys.stdout  # (with --json, stdout is JSON only)
    # The bus layer's queue (DEFAULT_QUEUE_CAPACITY) holds the progress that arrives while
    # an RPC is in flight; nothing else keeps this loop from the bus.
    follow = TaskFollow(bus, client, intr, args.watch, as_json, args.verbose)
    manager = ManagerWatch(bus)
    try:
        task = call(client, "start", req, skill_task_t, intr)
    except RpcError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    follow.task = task.task
    manager.started(task)
    if args.detach:
        print(f"task {task.task}: {req.type} started, detached (stop it with: skillbus stop {task.task})",
              file=sys.stderr, flush=True)
        print(json.dumps({"task": task.task, "skill": req.type, "detached": True}) if as_json else task.task,
              flush=True)
        return 0
    print(f"task {task.task}: {req.type} started", file=say, flush=True)
    return _follow_to_end(follow, manager, args, intr, req.type, req.label, say, stop_when_abandoned=True)


class TaskFollow:
    """Follows one task's progress: each tree once, in tick order, printed as --watch
    asks; when nothing is heard of it for CATCH_UP_S, the manager's latest tree
    (SKILL.tasks), so lost messages, the last ones above all, do not leave it hanging."""

    def __init__(self, bus, client: RpcClient, intr: Interrupts, watch: bool, as_json: bool, verbose: bool) -> None:
        self.bus, self.client, self.intr = bus, client, intr
        self.watch, self.as_json = watch, as_json
        self.task: int | None = None
        self.final: list[skill_progress_t] = []
        self.last: skill_progress_t | None = None
        self._changes = ChangePrinter(verbose)
        self._last_shown = None
        self._heard = time.monotonic()
        bus.subscribe(channel("SB_SKILL_PROGRESS"), self._on_progress)

    def _on_progress(self, ch, data) -> None:
        p = decode(skill_progress_t, data)
        if p is not None and self.task is not None and p.task == self.task:
            self.take(p)

    def take(self, p: skill_progress_t) -> None:
        self._heard = time.monotonic()
        if self.final or (self.last is not None and p.tick < self.last.tick):
            return  # (a catch-up answer that crossed a newer message)
        self.last = p
        if self.watch:
            if self.as_json:
                # (each new progress code is a new line: a step that repeats its message still counts up)
                shown = [(n.state, n.message, n.code) for n in p.nodes]
                if shown != self._last_shown:
                    self._last_shown = shown
                    print(json.dumps(progress_json(p)), flush=True)
            else:
                self._changes.print(p)
        if p.state in (State.Success, State.Failure):
            self.final.append(p)

    def catch_up(self) -> bool:
        """Takes the manager's latest tree of the task; False when it does not know it."""
        self._heard = time.monotonic()
        p = latest_progress(self.client, self.task, self.intr)
        if p is not None:
            self.take(p)
        return p is not None

    def step(self, s: float) -> None:
        self.intr.handle(self.bus, s)
        if not self.final and time.monotonic() - self._heard > CATCH_UP_S:
            # Nothing heard for a while: lost messages or a paused task; the manager says which.
            self.catch_up()


def _follow_to_end(follow: TaskFollow, manager: "ManagerWatch", args, intr: Interrupts, skill: str, label: str,
                   say, stop_when_abandoned: bool) -> int:
    """Waits for the task's end (or --timeout, a signal, a lost manager) and prints it;
    the exit code. An abandoned task is stopped when we started it."""
    task, as_json = follow.task, getattr(args, "json", False)
    timeout = getattr(args, "timeout", 0.0)
    final = follow.final
    poll_until(lambda: final or intr.signum or manager.lost(task), timeout if timeout > 0 else math.inf,
               interval=0.2, step=follow.step)
    code = None
    lost = "" if final else manager.lost(task)
    if lost and not intr.signum:
        print(f"task {task}: Failure: {lost}", file=say, flush=True)
        code = 1
    elif not final and intr.signum:
        print(f"interrupted ({intr.name})" + (f": stopping task {task}" if stop_when_abandoned else ""),
              file=sys.stderr, flush=True)
        code = intr.exit_code
    elif not final:
        print(f"error: task {task} did not end within {timeout} s" + (": stopping it" if stop_when_abandoned else ""),
              file=sys.stderr, flush=True)
        code = EXIT_TIMEOUT
    if code is not None and not final and not lost and stop_when_abandoned:
        _stop(follow.client, follow.bus, task, final, intr)
    if code is None:
        code = 0 if final[0].state == State.Success else 1
    if as_json:
        # the final tree, or when its end was not seen, the last one (state Running, ...)
        p = final[0] if final else follow.last
        tree = progress_json(p) if p is not None else None
        root = p.nodes[0] if p is not None and p.nodes else None
        print(json.dumps({"task": task, "skill": skill or (root.type if root else ""), "label": label,
                          "state": STATES[p.state] if final else ("Failure" if lost else None),
                          "message": lost or (root.message if root else ""),
                          "ended": bool(final), "exit_code": code, "tick": tree["tick"] if tree else None,
                          "tree": tree["nodes"] if tree else []}), flush=True)
    elif final:
        p = final[0]
        if not follow.watch:
            print_tree(p, args.verbose)
        root = p.nodes[0]
        print(f"task {p.task}: {STATES[p.state]}" + (f": {root.message}" if root.message else ""), flush=True)
    return code


def watch(args, intr: Interrupts) -> int:
    """`skillbus watch TASK`: follows a task started elsewhere (a console, another shell,
    the manager's --start) from its current tree to its end; the exit code as run's. An
    interrupt or --timeout leaves the task running."""
    from skillbus.monitor import watch_url
    bus = open_bus(watch_url(args.url))
    client = RpcClient(bus, "SKILL", "cli")
    as_json = args.json
    follow = TaskFollow(bus, client, intr, True, as_json, args.verbose)
    manager = ManagerWatch(bus)
    follow.task = args.task
    try:
        found = call(client, "tasks", _task_req(args.task), skill_progress_list_t, intr)
    except RpcRemoteError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    p = next((t for t in found.tasks if t.task == args.task), None)
    if p is None:
        print(f"error: the skill manager does not know task {args.task}", file=sys.stderr)
        return 2
    say = sys.stderr if as_json else sys.stdout
    print(f"task {args.task}: {p.nodes[0].type if p.nodes else '?'}, watching from tick {p.tick}", file=say, flush=True)
    follow.take(p)
    return _follow_to_end(follow, manager, args, intr, "", "", say, stop_when_abandoned=False)


def _task_req(task: int) -> skill_start_t:
    req = skill_start_t()
    req.task = task
    return req


def latest_progress(client: RpcClient, task: int, intr: Interrupts | None = None) -> skill_progress_t | None:
    """The manager's latest tree of `task` (SKILL.tasks), or None when it does not know it
    (any more), does not answer, or is too old to have the method."""
    try:
        reply = call(client, "tasks", _task_req(task), skill_progress_list_t, intr)
    except (NoManager, RpcError):
        return None
    return next((p for p in reply.tasks if p.task == task), None)


def _stop(client: RpcClient, bus, task: int, final: list, intr: Interrupts) -> None:
    """Preempts an abandoned task: SKILL.stop, acknowledged within STOP_ACK_TIMEOUT, then
    its final progress, within FINAL_TIMEOUT (a further signal ends that wait)."""
    req = skill_start_t()
    req.task = task
    try:
        call(client, "stop", req, skill_task_t, intr, timeout=STOP_ACK_TIMEOUT)
    except RpcRemoteError as e:  # it ended meanwhile ("no running task"): its progress may be in
        if not final:
            intr.handle(bus, 0.0)
        if not final:
            print(f"error: stop task {task}: {e}", file=sys.stderr)
        return
    except NoManager as e:
        print(f"error: task {task} may still be running: {e}", file=sys.stderr)
        return
    seen = intr.count
    poll_until(lambda: final or intr.count != seen, FINAL_TIMEOUT, interval=0.2, step=lambda s: intr.handle(bus, s))
    if not final:
        print(f"task {task}: stop acknowledged; its end was not seen"
              + (f" within {FINAL_TIMEOUT:g} s" if intr.count == seen else " (interrupted again)"), file=sys.stderr)


def main(args: argparse.Namespace) -> int:
    if args.command == "skills-process":
        from skillbus.skill import process
        return process.main(args)
    if args.command == "run":
        return run(args)
    if args.command == "watch":
        return _with_manager(watch, args)
    if args.command in ("skills", "stop", "pause", "resume", "step"):
        return _with_manager(_command, args)
    return 2


def _command(args, intr: Interrupts) -> int:
    """skills, stop, pause, resume, step: one call to the manager each."""
    bus = open_bus(args.url)
    if args.command == "skills" and args.robot is None and not os.environ.get("SKILLBUS_ROBOT"):
        return _every_managers_skills(bus, args, intr)
    client = RpcClient(bus, "SKILL", "cli")
    if args.command == "skills":
        return _one_managers_skills(client, args, intr)
    req = skill_start_t()
    req.task = args.task
    try:
        print(f"task {args.task}: {call(client, args.command, req, skill_task_t, intr).message}")
    except RpcError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return intr.exit_code if intr.signum else 0


def _one_managers_skills(client: RpcClient, args, intr: Interrupts) -> int:
    """`skillbus skills` of the manager `client` talks to: its list, or JSON."""
    try:
        lst = call(client, "list", skill_start_t(), skill_list_t, intr)
    except RpcError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    if intr.signum:
        return intr.exit_code
    if args.json:
        print(json.dumps(skills_json(lst)))
    else:
        print_skills(lst)
    return 0


def _every_managers_skills(bus, args, intr: Interrupts) -> int:
    """`skillbus skills` without --robot: the skills of every manager that answers a probe,
    under a heading per robot. With one manager and no robot names, as before: its list
    alone (and a manager too old to answer the probe is asked directly)."""
    from skillbus.skill.managers import discover
    managers = discover(bus)
    if intr.signum:
        return intr.exit_code
    if not managers or (len(managers) == 1 and not managers[0].robot):
        return _one_managers_skills(RpcClient(bus, "SKILL", "cli", robot=""), args, intr)
    out: list[dict[str, Any]] = []
    failed = 0
    for m in managers:
        try:
            lst = call(RpcClient(bus, "SKILL", "cli", robot=m.robot), "list", skill_start_t(), skill_list_t, intr)
        except (NoManager, RpcError) as e:
            print(f"error: robot {m.robot or '(none)'}: {e}", file=sys.stderr)
            failed += 1
            continue
        if intr.signum:
            return intr.exit_code
        if args.json:
            out += [dict(skill, robot=m.robot, manager=m.name) for skill in skills_json(lst)]
        else:
            agent = f", driving {m.agent}" if m.agent else ""
            print(f"== robot {m.robot or '(none)'}: skill manager {m.name}{agent}, {len(lst.skills)} skills ==")
            print_skills(lst)
    if args.json:
        print(json.dumps(out))
    return 1 if failed else 0
