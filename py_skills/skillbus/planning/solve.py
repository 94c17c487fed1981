"""Plans with Fast Downward through Unified Planning: satisficing (LAMA's first search)
or optimal (A* with an admissible heuristic: the fewest skills), within a time limit.
When there is no plan, each goal is tried on its own to name the ones that cannot be
reached at all."""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from skillbus.planning import domain as domains
from skillbus.planning.goals import Goal, parse_goals
from skillbus.planning.model import SkillSpec, World

ENGINES = {False: "fast-downward", True: "fast-downward-opt"}
DEFAULT_TIME_LIMIT_S = 10.0


class PlanError(RuntimeError):
    pass


@dataclass
class Step:
    skill: SkillSpec
    params: dict[str, str]  # parameter key -> element id

    def __str__(self) -> str:
        return f"{self.skill.type} ({self.skill.label}) " + " ".join(f"{k}={v}" for k, v in self.params.items())


@dataclass
class Plan:
    steps: list[Step]
    goals: list[Goal]
    domain: domains.Domain
    engine: str
    seconds: float
    left_out: dict[str, str] = field(default_factory=dict)


def _engine():
    from unified_planning.shortcuts import get_environment
    env = get_environment()
    env.credits_stream = None  # (the engines' banners are not our output)
    return env


def _solve(problem: Any, optimal: bool, time_limit: float) -> Any:
    """The engine's result; PlanError naming the engine when it cannot run at all (not
    installed, failing): one line, not the library's traceback."""
    try:
        return _solve_with_engine(problem, optimal, time_limit)
    except ImportError as e:
        raise PlanError(f"the planner cannot run: {e} (deploy/setup.sh installs unified-planning and "
                        f"up-fast-downward)") from None
    except Exception as e:  # (UPNoRequestedEngineAvailableException has no message: its type says it)
        raise PlanError(f"the planner {ENGINES[optimal]} failed: {type(e).__name__}"
                        f"{': ' + str(e) if str(e) else ''}") from None


def _solve_with_engine(problem: Any, optimal: bool, time_limit: float) -> Any:
    from unified_planning.shortcuts import OneshotPlanner
    _engine()
    with warnings.catch_warnings():
        # The optimal engine (A* with LM-cut) does not take conditional effects, which the
        # containment rule writes (out of every other container); Fast Downward's
        # translator grounds them away (the condition is an equality of parameters), so
        # the search sees none and its plans are the shortest. Unified Planning cannot
        # know that and warns.
        warnings.filterwarnings("ignore", message="We cannot establish whether")
        with OneshotPlanner(name=ENGINES[optimal]) as planner:
            _private_sas_file(planner)
            return planner.solve(problem, timeout=time_limit)


def _private_sas_file(planner: Any) -> None:
    """Fast Downward's driver writes its translated task to output.sas in the current
    folder: two plans made at once from one folder (two robots' skill processes under
    supervisord, which start them in the repository) read each other's task and answered
    another problem's plan, or none. The file goes beside the plan file, in the engine's
    own temporary folder."""
    import os
    base = getattr(planner, "_base_cmd", None)
    if base is None:
        raise PlanError(f"the planner {type(planner).__name__} is not the Fast Downward engine this was made for")

    def cmd(plan_filename: str) -> list:
        return base(plan_filename) + ["--sas-file", os.path.join(os.path.dirname(plan_filename), "output.sas")]
    planner._base_cmd = cmd


def _solved(status: Any) -> bool:
    from unified_planning.engines import PlanGenerationResultStatus as S
    return status in (S.SOLVED_SATISFICING, S.SOLVED_OPTIMALLY)


def _unsolvable(status: Any) -> bool:
    from unified_planning.engines import PlanGenerationResultStatus as S
    return status in (S.UNSOLVABLE_PROVEN, S.UNSOLVABLE_INCOMPLETELY)


def make_plan(skills: list[SkillSpec], world: World, goal_text: str, optimal: bool = False,
              time_limit: float = DEFAULT_TIME_LIMIT_S, pddl_dir: Path | None = None) -> Plan:
    """The skills that reach the goals from the world as it is, within `time_limit` in all
    (the search and, when there is no plan, the explanation). GoalError for a malformed
    goal or one naming what the domain lacks; PlanError when there is no plan (naming the
    goals that cannot be reached), none within the time limit, or the planner failed.
    With `pddl_dir` the domain and problem are written there first (plan or not)."""
    from unified_planning.engines import PlanGenerationResultStatus as S
    goals = parse_goals(goal_text)
    d = domains.build(skills, world, goals)
    if pddl_dir is not None:
        try:
            write_pddl(d, pddl_dir)
        except OSError as e:
            raise PlanError(f"cannot write the PDDL into {pddl_dir}: {e.strerror or e}") from None
    t0 = time.monotonic()
    result = _solve(d.problem, optimal, time_limit)
    seconds = time.monotonic() - t0
    if result.status == S.TIMEOUT:
        raise PlanError(f"no plan within the planner's time limit of {time_limit:g} s ({ENGINES[optimal]}) for "
                        f"{len(goals)} goal(s)")
    if _unsolvable(result.status):
        raise PlanError(explain(skills, world, goals, d, optimal, max(0.0, time_limit - seconds)))
    if not _solved(result.status):  # (out of memory, an internal error, a problem it does not take)
        raise PlanError(f"the planner {ENGINES[optimal]} ended with {result.status.name} for {len(goals)} goal(s)"
                        + _engine_log(result))
    by_object = {obj.name: eid for eid, obj in d.objects.items()}
    steps = []
    for ai in result.plan.actions:
        skill = d.actions[ai.action.name]
        values = [by_object[p.object().name] for p in ai.actual_parameters]
        steps.append(Step(skill, {k: v for (k, _), v in zip(skill.params, values)}))
    return Plan(steps, goals, d, ENGINES[optimal], seconds, dict(d.left_out))


def explain(skills: list[SkillSpec], world: World, goals: list[Goal], d: domains.Domain, optimal: bool,
            time_limit: float) -> str:
    """Why there is no plan: the goals that cannot be reached even on their own, else that
    they cannot be reached together; within `time_limit` in all (what is left of the
    caller's), a goal not decided within it said as such."""
    alone, undecided = [], []
    deadline = time.monotonic() + time_limit
    for g in goals:
        left = deadline - time.monotonic()
        if left <= 0.05:
            undecided.append(str(g))
            continue
        r = _solve(domains.build(skills, world, [g]).problem, optimal, left)
        if _unsolvable(r.status):
            alone.append(str(g))
        elif not _solved(r.status):
            undecided.append(str(g))
    skills_note = f"; skills left out: {', '.join(f'{k} ({v})' for k, v in sorted(d.left_out.items()))}" \
        if d.left_out else ""
    unknown = (f"; not decided within the time limit, on its own: {', '.join(undecided)}" if undecided else "")
    if alone:
        return (f"no plan: no sequence of the skills ({', '.join(sorted(d.actions)) or 'none'}) reaches "
                f"{', '.join(alone)} from the world as it is{unknown}{skills_note}")
    if undecided:
        return (f"no plan for all {len(goals)} goal(s) together ({', '.join(map(str, goals))}){unknown}"
                f"{skills_note}")
    return (f"no plan: each goal can be reached on its own, but not all {len(goals)} together "
            f"({', '.join(map(str, goals))}){skills_note}")


def _engine_log(result: Any) -> str:
    """The engine's own last words, when it said any."""
    lines = [str(getattr(m, "message", m)).strip() for m in getattr(result, "log_messages", None) or []]
    lines = [x for x in lines if x]
    return f": {lines[-1][:500]}" if lines else ""


def write_pddl(d: domains.Domain, folder: Path) -> tuple[Path, Path]:
    """domain.pddl and problem.pddl of the problem (Unified Planning's PDDL writer)."""
    from unified_planning.io import PDDLWriter
    folder.mkdir(parents=True, exist_ok=True)
    w = PDDLWriter(d.problem)
    dom, prob = folder / "domain.pddl", folder / "problem.pddl"
    w.write_domain(str(dom))
    w.write_problem(str(prob))
    return dom, prob
