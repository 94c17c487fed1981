"""Goals as SkiROS2 writes them (its TaskPlan skill's Goal parameter): facts in
parentheses, separated by commas, each a predicate and one or two element ids; skillbus
also takes "(not (...))" and any spacing.

    >>> parse_goals("(skiros:contain skiros:Bin-5 skiros:Cube-2), (skiros:contain skiros:Bin-5 skiros:Cube-4)")
    [Goal(predicate='skiros:contain', args=('skiros:Bin-5', 'skiros:Cube-2'), positive=True), Goal(predicate='skiros:contain', args=('skiros:Bin-5', 'skiros:Cube-4'), positive=True)]
    >>> parse_goals("(not (skiros:contain skiros:Gripper-7 skiros:Cube-2))")[0].positive
    False
    >>> parse_goals("(skiros:contain skiros:Bin-5")
    Traceback (most recent call last):
    ...
    skillbus.planning.goals.GoalError: goal 1 '(skiros:contain skiros:Bin-5': a '(' is not closed
"""

from __future__ import annotations

import re
from dataclasses import dataclass

TOKEN = re.compile(r"\(|\)|,|[^\s(),]+")


class GoalError(ValueError):
    pass


@dataclass(frozen=True)
class Goal:
    predicate: str
    args: tuple[str, ...]
    positive: bool = True

    def __str__(self) -> str:
        fact = f"({self.predicate} {' '.join(self.args)})"
        return fact if self.positive else f"(not {fact})"


def _split(text: str) -> list[str]:
    """The goal string's top-level facts (commas inside parentheses do not split)."""
    parts, depth, cur = [], 0, []
    for ch in text:
        if ch == "," and depth == 0:
            parts.append("".join(cur))
            cur = []
            continue
        depth += ch == "("
        depth -= ch == ")"
        cur.append(ch)
    parts.append("".join(cur))
    return [p.strip() for p in parts if p.strip()]


def _parse_one(text: str, n: int) -> Goal:
    where = f"goal {n} {text!r}"
    tokens = TOKEN.findall(text)

    def fact(toks: list[str]) -> Goal:
        if len(toks) < 3 or toks[0] != "(" or toks[-1] != ")":
            raise GoalError(f"{where}: a fact is (predicate element) or (predicate element element)")
        inner = toks[1:-1]
        if inner and inner[0] == "not":
            g = fact(inner[1:])
            if not g.positive:
                raise GoalError(f"{where}: (not (not ...)) is the fact itself; write it so")
            return Goal(g.predicate, g.args, False)
        if "(" in inner or ")" in inner or "," in inner:
            raise GoalError(f"{where}: a fact is (predicate element) or (predicate element element)")
        if not 2 <= len(inner) <= 3:
            raise GoalError(f"{where}: a fact names a predicate and one or two elements, not {len(inner) - 1}")
        return Goal(inner[0], tuple(inner[1:]))

    depth = 0
    for t in tokens:
        depth += t == "("
        depth -= t == ")"
        if depth < 0:
            raise GoalError(f"{where}: a ')' closes nothing")
    if depth > 0:
        raise GoalError(f"{where}: a '(' is not closed")
    return fact(tokens)


def parse_goals(text: str) -> list[Goal]:
    """The goals of a Goal string; GoalError names the one that is malformed."""
    if not text or not text.strip():
        raise GoalError("no goal: give facts such as (skiros:contain skiros:Bin-5 skiros:Cube-2), separated by commas")
    return [_parse_one(part, i + 1) for i, part in enumerate(_split(text))]
