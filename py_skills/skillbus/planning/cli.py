"""`skillbus plan "GOAL"`: the plan the task planner finds for goals, from the skills a
skill manager has registered and the world model as it is; `--pddl DIR` writes the domain
and problem it solved. Exit 0 with a plan, 1 when there is none (why, on stderr), 2 for a
malformed goal or one naming what the world or the skills lack."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from skillbus import cli_values

ROBOT_HELP = "the robot whose skill manager's skills to plan with (default: the one without a robot name)"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("plan", help="plan skills for goals (Fast Downward), print the plan (docs/planning.md)")
    p.add_argument("goal", help='facts, comma-separated: "(skiros:contain skiros:Bin-5 skiros:Cube-2), (...)"')
    p.add_argument("--optimal", action="store_true", help="the fewest skills (A* with LM-cut), not the first plan")
    p.add_argument("--time-limit", type=cli_values.seconds, default=10.0, metavar="S", help="seconds of planning at most")
    p.add_argument("--pddl", type=Path, metavar="DIR", help="also write domain.pddl and problem.pddl there")
    p.add_argument("--json", action="store_true", help="the plan as one JSON object")
    p.add_argument("--url", default=None)
    p.add_argument("--robot", default=None, metavar="NAME", help=ROBOT_HELP)


def main(args: argparse.Namespace) -> int:
    from skillbus.bus import open_bus
    from skillbus.msgs import skill_list_t, skill_start_t
    from skillbus.planning.goals import GoalError
    from skillbus.planning.model import skill_from_msg, world_from_client
    from skillbus.planning.solve import PlanError, make_plan
    from skillbus.rpc import RpcClient, RpcError
    from skillbus.world.client import WorldModelError, WorldModelInterface
    try:
        bus = open_bus(args.url)
        lst = RpcClient(bus, "SKILL", "plan", robot=args.robot).call("list", skill_start_t(), skill_list_t, timeout=5.0)
        wmi = WorldModelInterface(bus, "plan")
        skills = [skill_from_msg(d) for d in lst.skills]
        plan = make_plan(skills, world_from_client(wmi), args.goal, optimal=args.optimal, time_limit=args.time_limit,
                         pddl_dir=args.pddl)
    except GoalError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except PlanError as e:
        print(f"error: {e}", file=sys.stderr)
        if args.pddl and (args.pddl / "problem.pddl").exists():  # (written before the search: a failed plan's need)
            print(f"PDDL: {args.pddl / 'domain.pddl'} {args.pddl / 'problem.pddl'}", file=sys.stderr)
        return 1
    except (RpcError, WorldModelError, OSError) as e:
        print(f"error: {e} (are the skill manager and the world model running, on this bus?)", file=sys.stderr)
        return 1
    files = (args.pddl / "domain.pddl", args.pddl / "problem.pddl") if args.pddl else None
    if args.json:
        print(json.dumps({"goals": [str(g) for g in plan.goals], "engine": plan.engine, "seconds": round(plan.seconds, 3),
                          "steps": [{"type": s.skill.type, "label": s.skill.label, "params": s.params} for s in plan.steps],
                          "left_out": plan.left_out, "pddl": [str(f) for f in files] if files else None}))
        return 0
    print(f"plan for {', '.join(map(str, plan.goals))} ({plan.engine}, {plan.seconds:.2f} s): {len(plan.steps)} step(s)")
    for i, s in enumerate(plan.steps, 1):
        print(f"  {i}. {s}")
    for label, why in sorted(plan.left_out.items()):
        print(f"  (left out: {label}: {why})")
    if files:
        print(f"  PDDL: {files[0]} {files[1]}")
    return 0
