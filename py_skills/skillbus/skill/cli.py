"""`skillbus skills`, `skillbus run`, `skillbus stop`, `skillbus skills-process`."""

from __future__ import annotations

import argparse
import json
import sys
import time

from skillbus.bus import channel, open_bus
from skillbus.msgs import decode, skill_list_t, skill_param_t, skill_progress_t, skill_start_t, skill_task_t
from skillbus.rpc import RpcClient, RpcError
from skillbus.skill.convert import value_msg
from skillbus.world.element import Element

STATES = {0: "Uninitialized", 1: "Idle", 2: "Running", 3: "Success", 4: "Failure"}
PARAM_TYPES = {0: "Required", 1: "Optional", 2: "Inferred"}


def add_parsers(sub) -> None:
    sp = sub.add_parser("skills-process", help="load skill libraries and serve them to a skill manager")
    sp.add_argument("--name", required=True, help="unique name of this process")
    sp.add_argument("--library", action="append", required=True, help="a Python module of skills (repeatable)")
    sp.add_argument("--url", default=None)
    sp.add_argument("--register-timeout", type=float, default=30.0)
    sp.add_argument("--lockstep", action="store_true", help="be a lockstep participant named --name")
    sp.add_argument("--gripper", default=None, metavar="CHANNEL[:NODE]",
                    help="drive a CANopen gripper on this CAN channel (node id, default 5) for the gripper skills")
    sp.add_argument("--can-interface", default="skillbus_vcan", help="python-can interface of --gripper")
    sp.add_argument("--arm", action="store_true",
                    help="give the skills the arm (robot state, trajectories, the motion service)")
    sp.add_argument("--world-model", action="store_true", help="give skills a world-model client (self.wmi)")
    ls = sub.add_parser("skills", help="the skills the manager knows, with parameters and conditions")
    ls.add_argument("--url", default=None)
    ls.add_argument("--json", action="store_true")
    run = sub.add_parser("run", help="run a skill; exit 0 on success")
    run.add_argument("skill", help="skill type (or implementation label with --label)")
    run.add_argument("--label", default="")
    run.add_argument("-p", "--param", action="append", default=[], metavar="KEY=VALUE")
    run.add_argument("--watch", action="store_true", help="show the live tree while it runs")
    run.add_argument("-v", "--verbose", action="store_true", help="show each primitive's parameters")
    run.add_argument("--timeout", type=float, default=0.0, help="give up after this many seconds (0: never)")
    run.add_argument("--url", default=None)
    for verb, text in (("stop", "preempt a running task"), ("pause", "stop ticking a task"),
                       ("resume", "tick a paused task again"), ("step", "tick a paused task once")):
        st = sub.add_parser(verb, help=text)
        st.add_argument("task", type=int)
        st.add_argument("--url", default=None)


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


def parse_param(text: str, lst: skill_list_t, skill: str) -> skill_param_t:
    if "=" not in text:
        raise ValueError(f"-p {text!r}: expected KEY=VALUE")
    key, raw = text.split("=", 1)
    decl = next((p for d in lst.skills if skill in (d.type, d.label) for p in d.params if p.key == key), None)
    if decl is None:
        raise ValueError(f"-p {key}: {skill} has no parameter {key!r}")
    conv = {"float": float, "int": int, "str": str, "bool": lambda s: s.lower() in ("1", "true", "yes"),
            "list": json.loads, "dict": json.loads}
    if decl.data_type == "element":
        value = Element(decl.concept or "Unknown", "", raw)
    else:
        try:
            value = conv[decl.data_type](raw)
        except (ValueError, KeyError) as e:
            raise ValueError(f"-p {key}: {raw!r} is not a {decl.data_type}: {e}") from None
    m = skill_param_t()
    m.key, m.data_type = key, decl.data_type
    m.values = [value_msg(value)]
    m.num_values = 1
    return m


def print_tree(p: skill_progress_t, verbose: bool = False) -> None:
    depth: dict[int, int] = {}
    for n in p.nodes:
        d = 0 if n.parent < 0 else depth[n.parent] + 1
        depth[n.id] = d
        name = n.type or f"({n.processor})"
        proc = f" [{n.processor}]" if n.processor and n.type else ""
        msg = f": {n.message}" if n.message else ""
        print(f"{'  ' * d}{name}{proc} {STATES.get(n.state, '?')}{msg}" + (f" (code {n.code})" if n.code else ""))
        if verbose and n.params:
            for line in n.params.strip().splitlines():
                print(f"{'  ' * (d + 2)}{line}")


def run(args) -> int:
    bus = open_bus(args.url)
    client = RpcClient(bus, "SKILL", "cli")
    lst = skill_list(client)
    req = skill_start_t()
    known = {d.type for d in lst.skills} | {d.label for d in lst.skills}
    if args.skill not in known:
        print(f"error: unknown skill {args.skill!r} (available: {', '.join(sorted({d.type for d in lst.skills})) or 'none'})",
              file=sys.stderr)
        return 2
    by_label = next((d for d in lst.skills if d.label == args.skill and d.type != args.skill), None)
    req.type, req.label = (by_label.type, by_label.label) if by_label else (args.skill, args.label)
    try:
        req.params = [parse_param(p, lst, args.skill) for p in args.param]
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    req.num_params = len(req.params)
    final: list[skill_progress_t] = []
    last_shown = [None]
    task_id = [None]

    def on_progress(ch, data):
        p = decode(skill_progress_t, data)
        if p is None or p.task != task_id[0]:
            return
        if args.watch:
            shown = [(n.state, n.message) for n in p.nodes]
            if shown != last_shown[0]:
                last_shown[0] = shown
                print(f"--- task {p.task}, tick {p.tick}")
                print_tree(p, args.verbose)
        if p.state in (3, 4):
            final.append(p)

    bus.subscribe(channel("SB_SKILL_PROGRESS"), on_progress)
    try:
        task = client.call("start", req, skill_task_t)
    except RpcError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    task_id[0] = task.task
    print(f"task {task.task}: {req.type} started", flush=True)
    deadline = time.monotonic() + args.timeout if args.timeout > 0 else None
    try:
        while not final:
            if deadline and time.monotonic() > deadline:
                print(f"error: task {task.task} did not end within {args.timeout} s", file=sys.stderr)
                return 3
            bus.handle(0.2)
    except KeyboardInterrupt:
        stop = skill_start_t()
        stop.task = task.task
        client.call("stop", stop, skill_task_t)
        print(f"stopping task {task.task}", file=sys.stderr)
        return 130
    p = final[0]
    if not args.watch:
        print_tree(p, args.verbose)
    root = p.nodes[0]
    print(f"task {p.task}: {STATES[p.state]}" + (f": {root.message}" if root.message else ""))
    return 0 if p.state == 3 else 1


def main(args: argparse.Namespace) -> int:
    if args.command == "skills-process":
        from skillbus.skill import process
        return process.main(args)
    if args.command == "skills":
        client = RpcClient(open_bus(args.url), "SKILL", "cli")
        try:
            lst = skill_list(client)
        except RpcError as e:
            print(f"error: {e}", file=sys.stderr)
            return 1
        if args.json:
            print(json.dumps([{"type": d.type, "label": d.label, "compound": d.compound, "process": p,
                               "params": [x.key for x in d.params]} for d, p in zip(lst.skills, lst.processes)]))
        else:
            print_skills(lst)
        return 0
    if args.command == "run":
        return run(args)
    if args.command in ("stop", "pause", "resume", "step"):
        client = RpcClient(open_bus(args.url), "SKILL", "cli")
        req = skill_start_t()
        req.task = args.task
        try:
            print(f"task {args.task}: {client.call(args.command, req, skill_task_t).message}")
        except RpcError as e:
            print(f"error: {e}", file=sys.stderr)
            return 1
        return 0
    return 2
