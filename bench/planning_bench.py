"""Task planning time (issue "Task planning"): a generated warehouse of 50 shelves and 100
products, a mobile robot with Drive, Fetch and Drop (skiros:at and skiros:contain
conditions, the skills of tests/integration/skill_libs/warehouse_skills.py), goals of 1, 5
and 20 products each brought to another shelf (seeded). skillbus's planner (the domain and
problem built from the skills and the world, Fast Downward's first plan through Unified
Planning) beside pyperplan (greedy best-first search with h_FF) given the same PDDL files,
in the same run; the ratio of their times; and skillbus's optimal mode (the fewest skills).

Run: .venv/bin/python bench/planning_bench.py   (in `make bench`)
"""

from __future__ import annotations

import json
import random
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from skillbus.planning import domain as domains
from skillbus.planning.goals import parse_goals
from skillbus.planning.model import Condition, SkillSpec, World
from skillbus.planning.solve import make_plan, write_pddl
from skillbus.world.ontology_view import OntologyView

SHELVES, PRODUCTS, SEED = 50, 100, 7
PYPERPLAN_LIMIT_S = 300.0
ONTOLOGY = OntologyView.from_json({"classes": {
    "sumo:Object": [], "skiros:PhysicalObject": ["sumo:Object"], "skiros:Location": ["skiros:PhysicalObject"],
    "skiros:Table": ["skiros:Location"], "skiros:Product": ["skiros:PhysicalObject"], "skiros:Cube": ["skiros:Product"],
    "skiros:Agent": ["skiros:PhysicalObject"], "skiros:Robot": ["skiros:Agent"]},
    "relations": {"skiros:contain": [], "skiros:at": []}, "individuals": {}})


def rel(owl: str, s: str, o: str, desired: bool = True) -> Condition:
    return Condition("Relation", s, o, owl, desired=desired)


SKILLS = [
    SkillSpec("Drive", "drive", [("Mover", "skiros:Robot"), ("From", "skiros:Location"), ("To", "skiros:Location")],
              pre=[rel("skiros:at", "Mover", "From")],
              post=[rel("skiros:at", "Mover", "From", False), rel("skiros:at", "Mover", "To")]),
    SkillSpec("Fetch", "fetch", [("Mover", "skiros:Robot"), ("Object", "skiros:Product"), ("Shelf", "skiros:Location")],
              pre=[rel("skiros:at", "Mover", "Shelf"), rel("skiros:contain", "Shelf", "Object")],
              post=[rel("skiros:contain", "Mover", "Object")]),
    SkillSpec("Drop", "drop", [("Mover", "skiros:Robot"), ("Object", "skiros:Product"), ("Shelf", "skiros:Location")],
              pre=[rel("skiros:at", "Mover", "Shelf"), rel("skiros:contain", "Mover", "Object")],
              post=[rel("skiros:contain", "Shelf", "Object")]),
]


def world(rng: random.Random) -> tuple[World, dict[str, str]]:
    types = {"skiros:Robot-1": "skiros:Robot"}
    shelves = [f"skiros:Table-{i + 2}" for i in range(SHELVES)]
    types.update({s: "skiros:Table" for s in shelves})
    on: dict[str, str] = {}
    relations = {("skiros:Robot-1", "skiros:at", shelves[0])}
    for i in range(PRODUCTS):
        p = f"skiros:Cube-{SHELVES + 2 + i}"
        types[p] = "skiros:Cube"
        on[p] = rng.choice(shelves)
        relations.add((on[p], "skiros:contain", p))
    return World(types, {}, relations, ONTOLOGY), on


def goals(rng: random.Random, on: dict[str, str], n: int) -> str:
    shelves = sorted(set(on.values()) | {"skiros:Table-2"})
    picked = rng.sample(sorted(on), n)
    return ", ".join(f"(skiros:contain {rng.choice([s for s in shelves if s != on[p]])} {p})" for p in picked)


def pyperplan(domain_file: Path, problem_file: Path) -> tuple[float | None, int | None]:
    """Seconds and plan length of pyperplan (gbf, hff) on the files; (None, None) past its limit."""
    t0 = time.monotonic()
    try:
        r = subprocess.run([sys.executable, "-m", "pyperplan", "-s", "gbf", "-H", "hff", str(domain_file),
                            str(problem_file)], capture_output=True, text=True, timeout=PYPERPLAN_LIMIT_S)
    except subprocess.TimeoutExpired:
        return None, None
    seconds = time.monotonic() - t0
    soln = Path(str(problem_file) + ".soln")
    if r.returncode != 0 or not soln.exists():
        raise RuntimeError(f"pyperplan failed: {r.stdout[-1000:]} {r.stderr[-1000:]}")
    return seconds, len([line for line in soln.read_text().splitlines() if line.strip().startswith("(")])


def main() -> int:
    rng = random.Random(SEED)
    w, on = world(rng)
    make_plan(SKILLS, w, goals(random.Random(0), on, 1))  # (Unified Planning's import and first call)
    rows = []
    print(f"task planning: {SHELVES} shelves, {PRODUCTS} products, a robot with Drive, Fetch, Drop (seed {SEED})")
    print(f"  {'goals':>5} {'skillbus (s)':>13} {'steps':>6} {'pyperplan (s)':>14} {'steps':>6} {'ratio':>7} "
          f"{'optimal (s)':>12} {'steps':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        for n in (1, 5, 20):
            text = goals(rng, on, n)
            t0 = time.monotonic()
            plan = make_plan(SKILLS, w, text)
            ours = time.monotonic() - t0
            t0 = time.monotonic()
            best = make_plan(SKILLS, w, text, optimal=True, time_limit=PYPERPLAN_LIMIT_S)
            optimal_s = time.monotonic() - t0
            d = domains.build(SKILLS, w, parse_goals(text))
            dom, prob = write_pddl(d, Path(tmp) / f"g{n}")
            theirs, their_steps = pyperplan(dom, prob)
            ratio = f"{theirs / ours:6.1f}x" if theirs else "   n/a"
            print(f"  {n:>5} {ours:>13.2f} {len(plan.steps):>6} "
                  f"{(f'{theirs:.2f}' if theirs else f'>{PYPERPLAN_LIMIT_S:.0f}'):>14} {their_steps or '-':>6} {ratio} "
                  f"{optimal_s:>12.2f} {len(best.steps):>6}", flush=True)
            rows.append({"goals": n, "skillbus_s": round(ours, 3), "skillbus_steps": len(plan.steps),
                         "pyperplan_s": round(theirs, 3) if theirs else None, "pyperplan_steps": their_steps,
                         "optimal_s": round(optimal_s, 3), "optimal_steps": len(best.steps)})
    print("  (skillbus: building the problem, writing it for Fast Downward, its translation and search; "
          "pyperplan: parsing, grounding and search of the same PDDL; ratio: pyperplan / skillbus; "
          "optimal: skillbus --optimal, A* with LM-cut, the fewest skills)")
    print(json.dumps({"planning": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
