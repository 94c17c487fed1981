"""Skills and the world as a Unified Planning problem.

Each skill the planner may use becomes an action named by its label; its element
parameters become typed parameters (the ontology's classes, with their hierarchy); its
pre- and hold-conditions become preconditions, its post-conditions effects:

    Relation                           (relation ?subject ?object), negated when not desired
    AbstractRelation (pre)             (may:relation ?subject ?object): what the ontology allows
                                       between their classes, a fact of its own (never the relation)
    HasProperty                        (has:Property ?subject)
    Property =                         (Property=value ?subject): setting one value clears the others
    Property <, <=, >, >=, != (pre)    (Property>value ?subject), true where the world has it so
    OnType (pre)                       (is:Concept ?subject)
    ConditionOr (pre)                  a disjunction of its members
    IsSpecified, Generate              not a fact of the world: left to the skill manager

skiros:contain (and the relations below it) keeps the world model's rule: an element is
in one container, so an effect that puts it into one takes it out of the one a
pre-condition says it is in, or (when none does) out of every other. A skill
with a condition that cannot be expressed (an OnType or Property comparison as an effect,
an Or among post-conditions, a parameter the ontology does not know) or with no effect is
left out, and `left_out` says why.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from skillbus.planning.goals import Goal, GoalError
from skillbus.planning.model import Condition, SkillSpec, World

ROOT = "thing"  # the root type: every class without a parent in the ontology sits below it
CONTAIN = "skiros:contain"
RUNTIME_ONLY = ("IsSpecified", "Generate")


class DomainError(ValueError):
    pass


def predicate_name(c: Condition) -> str:
    """The predicate a condition is about (also what a goal names)."""
    if c.kind == "Relation":
        return c.owl
    if c.kind == "AbstractRelation":  # (not the relation itself: a bin may contain a cube it does not)
        return f"may:{c.owl}"
    if c.kind == "HasProperty":
        return f"has:{c.owl}"
    if c.kind == "OnType":
        return f"is:{c.owl}"
    if c.kind == "Property":
        return f"{c.owl}{c.op}{value_text(c.value)}"
    raise DomainError(f"a {c.kind} condition is no fact of the world")


def value_text(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    return str(v)


def compare(have: Any, op: str, value: Any) -> bool:
    try:
        if op == "=":
            return have == value
        if op == "!=":
            return have != value
        return {"<": have < value, "<=": have <= value, ">": have > value, ">=": have >= value}[op]
    except (TypeError, KeyError):
        return False


@dataclass
class Domain:
    problem: Any                                   # unified_planning.model.Problem
    actions: dict[str, SkillSpec]                  # action name -> the skill
    left_out: dict[str, str]                       # skill label -> why it is not an action
    predicates: dict[str, tuple[Condition, int]]   # predicate -> an example condition, its arity
    objects: dict[str, Any] = field(default_factory=dict)  # element id -> UP object
    notes: list[str] = field(default_factory=list)


class _Builder:
    def __init__(self, skills: list[SkillSpec], world: World) -> None:
        from unified_planning.shortcuts import BoolType, UserType
        self.UserType, self.BoolType = UserType, BoolType
        self.skills, self.world = skills, world
        self.onto = world.ontology
        self.types: dict[str, Any] = {ROOT: UserType(ROOT)}
        self.fluents: dict[str, Any] = {}
        self.predicates: dict[str, tuple[Condition, int]] = {}
        self.left_out: dict[str, str] = {}
        self.notes: list[str] = []
        self.wanted: set[str] = set()  # parameter concepts of the actions: which parent to keep of several
        self.may: dict[tuple[str, str, str], bool] = {}

    # -- types ------------------------------------------------------------------------
    def parent(self, concept: str) -> str | None:
        """The one parent a class keeps (a planning type has one): of several, one through
        which a parameter's concept is reached, else the first by name."""
        ups = self.onto.parents("classes", concept)
        if not ups:
            return None
        useful = [u for u in ups if any(self.onto.is_below("classes", u, w) for w in self.wanted)]
        return (useful or ups)[0]

    def type_of(self, concept: str) -> Any:
        if concept not in self.types:
            up = self.parent(concept)
            father = self.type_of(up) if up else self.types[ROOT]
            self.types[concept] = self.UserType(concept, father)
        return self.types[concept]

    def reaches(self, concept: str, ancestor: str) -> bool:
        """Whether `concept` is below `ancestor` along the parents kept."""
        cur: str | None = concept
        while cur is not None:
            if cur == ancestor:
                return True
            cur = self.parent(cur)
        return False

    # -- predicates -------------------------------------------------------------------
    def fluent(self, c: Condition) -> Any:
        from unified_planning.shortcuts import Fluent
        name = predicate_name(c)
        arity = 2 if c.kind in ("Relation", "AbstractRelation") else 1
        if name not in self.fluents:
            params = {"a": self.types[ROOT], "b": self.types[ROOT]} if arity == 2 else {"a": self.types[ROOT]}
            self.fluents[name] = Fluent(self.fluent_name(name), self.BoolType(), **params)
            self.predicates[name] = (c, arity)
        return self.fluents[name]

    def fluent_name(self, predicate: str) -> str:
        """The predicate's name as Unified Planning takes it, one of its own: comparisons
        other than = spelled out (Weight<1.0 and Weight>1.0 both became Weight_1.0, and
        building the problem failed), and a name that still collides numbered."""
        words = re.sub(r"<=|>=|!=|<|>|=", lambda m: _OPERATOR_WORDS[m.group(0)], predicate, count=1) \
            if not predicate.startswith(("has:", "is:", "may:")) else predicate
        base = name = safe(words)
        taken = {f.name for f in self.fluents.values()}
        n = 1
        while name in taken:
            n += 1
            name = f"{base}_{n}"
        return name

    def check_skill(self, s: SkillSpec) -> str:
        """Why the skill cannot be an action ("" when it can)."""
        if not s.for_planning:
            return "it is not available for planning (available_for_planning = False)"
        keys = {k for k, _ in s.params}
        for key, concept in s.params:
            if not self.onto.knows("classes", concept):
                return f"parameter {key}'s concept {concept} is not in the ontology"
        for where, cs in (("pre", s.pre), ("hold", s.hold), ("post", s.post)):
            for c in cs:
                if c.kind in RUNTIME_ONLY:
                    continue
                if c.kind not in ("Relation", "AbstractRelation", "HasProperty", "Property", "OnType"):
                    return f"its {where}-condition of kind {c.kind} cannot be expressed"
                for key in (c.subject, c.object) if c.kind in ("Relation", "AbstractRelation") else (c.subject,):
                    if key not in keys:
                        return (f"its {where}-condition {c.kind} {c.owl} names parameter {key!r}, which is not an "
                                f"element parameter the planner binds")
                if where == "post":
                    if c.or_label:
                        return "a ConditionOr among its post-conditions: an effect must be certain"
                    if c.kind in ("OnType", "AbstractRelation"):
                        return f"its post-condition {c.kind} {c.owl} is not a fact a skill can make true"
                    if c.kind == "Property" and c.op != "=":
                        return f"its post-condition {c.owl} {c.op} {c.value!r} does not say which value results"
        if not [c for c in s.post if c.kind not in RUNTIME_ONLY]:
            return "it has no post-condition: nothing for the planner to reach with it"
        return ""

    # -- actions ----------------------------------------------------------------------
    def planning_type_of(self, concept: str) -> tuple[Any, bool]:
        """A parameter's planning type, and whether it needs an (is:Concept ?p) precondition:
        when an element of the concept reaches it only through a parent the one-parent
        hierarchy did not keep (a Robot below sumo:Agent and skiros:PhysicalObject, the
        latter kept for another skill), the concept's type would not take it, and the
        parameter is typed by the root and checked by the ontology instead."""
        lost = any(self.world.is_a(eid, concept) and not self.reaches(t, concept)
                   for eid, t in sorted(self.world.types.items()))
        return (self.types[ROOT], True) if lost else (self.type_of(concept), False)

    def action(self, s: SkillSpec) -> Any:
        from unified_planning.shortcuts import Equals, InstantaneousAction, Not, Or, Variable
        typed = {k: self.planning_type_of(concept) for k, concept in s.params}
        act = InstantaneousAction(safe(s.name), **{safe(k): typed[k][0] for k, _ in s.params})
        p = {k: act.parameter(safe(k)) for k, _ in s.params}
        for k, concept in s.params:
            if typed[k][1]:
                act.add_precondition(self.fluent(Condition("OnType", k, "", concept))(p[k]))

        def atom(c: Condition) -> Any:
            f = self.fluent(c)
            args = (p[c.subject], p[c.object]) if c.kind in ("Relation", "AbstractRelation") else (p[c.subject],)
            return f(*args) if c.desired else Not(f(*args))

        groups: dict[str, list[Any]] = {}
        for c in [*s.pre, *s.hold]:
            if c.kind in RUNTIME_ONLY:
                continue
            if c.or_label:
                groups.setdefault(c.or_label, []).append(atom(c))
            else:
                act.add_precondition(atom(c))
        for members in groups.values():
            act.add_precondition(Or(*members) if len(members) > 1 else members[0])
        for c in s.post:
            if c.kind in RUNTIME_ONLY:
                continue
            f = self.fluent(c)
            if c.kind == "Relation":
                subj, obj = p[c.subject], p[c.object]
                if c.desired and self.onto.is_below("relations", c.owl, CONTAIN):
                    # Into one container: out of every other (the world model's rule). When a
                    # pre-condition names the container it is in, out of that one (plain
                    # STRIPS: a delete, which an add of the same fact overrides); else out of
                    # whatever holds it (a conditional effect over every element).
                    olds = [q for q in [*s.pre, *s.hold] if q.kind == "Relation" and q.desired and not q.or_label
                            and q.object == c.object and q.subject != c.subject and q.owl == c.owl]
                    for q in olds:
                        act.add_effect(f(p[q.subject], obj), False)
                    if not olds:
                        z = Variable("z", self.types[ROOT])
                        act.add_effect(f(z, obj), False, condition=Not(Equals(z, subj)), forall=[z])
                act.add_effect(f(subj, obj), c.desired)
            elif c.kind == "Property" and c.desired:
                act.add_effect(f(p[c.subject]), True)
                self.exclusive.setdefault(c.owl, set()).add(predicate_name(c))
                self.setters.append((act, c, p[c.subject]))
            else:
                act.add_effect(f(p[c.subject]), c.desired)
        return act

    def build(self, goals: list[Goal]) -> Domain:
        from unified_planning.shortcuts import Object
        usable = []
        for s in self.skills:
            why = self.check_skill(s)
            if why:
                self.left_out[s.label] = why
            else:
                usable.append(s)
                self.wanted.update(concept for _, concept in s.params)
        self.exclusive: dict[str, set[str]] = {}
        self.setters: list[tuple[Any, Condition, Any]] = []
        actions = {safe(s.name): s for s in usable}
        built = [self.action(s) for s in usable]
        # Setting a property's value clears its other values the domain knows.
        for act, c, subject in self.setters:
            for other in sorted(self.exclusive[c.owl] - {predicate_name(c)}):
                act.add_effect(self.fluents[other](subject), False)

        problem = _problem_class()("skillbus")
        for name in sorted(self.fluents):
            problem.add_fluent(self.fluents[name], default_initial_value=False)
        for a in built:
            problem.add_action(a)

        # Objects: the elements any action parameter could take, and those the goals name.
        named = {a for g in goals for a in g.args}
        for g in goals:
            if g.predicate not in self.predicates:
                known = ", ".join(sorted(self.predicates)) or "none"
                raise GoalError(f"goal {g}: no skill the planner can use has {g.predicate} in its conditions "
                                f"(the predicates it knows: {known})")
            if len(g.args) != self.predicates[g.predicate][1]:
                raise GoalError(f"goal {g}: {g.predicate} takes {self.predicates[g.predicate][1]} element(s)")
            for a in g.args:
                if a not in self.world.types:
                    raise GoalError(f"goal {g}: the world model has no element {a}")
        objects: dict[str, Any] = {}
        for eid in sorted(self.world.types):
            etype = self.world.types[eid]
            if not self.onto.knows("classes", etype):
                if eid in named:
                    raise GoalError(f"element {eid}'s type {etype} is not in the ontology")
                continue
            if eid in named or any(self.reaches(etype, w) for w in self.wanted):
                objects[eid] = Object(safe(eid), self.type_of(etype))
        problem.add_objects(list(objects.values()))
        self.initial_state(problem, objects)
        for g in goals:
            fact = self.fluents[g.predicate](*(objects[a] for a in g.args))
            problem.add_goal(fact if g.positive else _not(fact))
        return Domain(problem, actions, self.left_out, self.predicates, objects, self.notes)

    def initial_state(self, problem: Any, objects: dict[str, Any]) -> None:
        w = self.world
        for name, (c, arity) in sorted(self.predicates.items()):
            f = self.fluents[name]
            if arity == 2 and c.kind == "AbstractRelation":  # what the ontology allows between their classes
                for s in objects:
                    for o in objects:
                        if s != o and self.onto_may_relate(w.types[s], c.owl, w.types[o]):
                            problem.set_initial_value(f(objects[s], objects[o]), True)
                continue
            if arity == 2:
                for s, rel, o in sorted(w.relations):
                    if s in objects and o in objects and self.onto.is_below("relations", rel, c.owl):
                        problem.set_initial_value(f(objects[s], objects[o]), True)
                continue
            for eid, obj in objects.items():
                props = w.properties.get(eid, {})
                if c.kind == "HasProperty":
                    holds = bool(props.get(c.owl))
                elif c.kind == "OnType":
                    holds = w.is_a(eid, c.owl)
                else:  # Property
                    values = props.get(c.owl) or []
                    holds = bool(values) and compare(values[0], c.op, c.value)
                if holds:
                    problem.set_initial_value(f(obj), True)

    def onto_may_relate(self, s_type: str, rel: str, o_type: str) -> bool:
        """Asked once per pair of classes (the world model answers it over RPC)."""
        key = (s_type, rel, o_type)
        if key not in self.may:
            checker = self.world.may_relate
            self.may[key] = bool(checker and checker(s_type, rel, o_type))
        return self.may[key]


_PROBLEM: Any = None


def _problem_class() -> Any:
    """Unified Planning's Problem, but its `initial_values` are the facts set true only.
    Every fluent here is Boolean with the default false, and that is all the PDDL writer
    writes; Unified Planning's own property lists every grounding of every fluent (45,000
    for two relations over 150 elements: 5 s of a 6 s plan)."""
    global _PROBLEM
    if _PROBLEM is None:
        from unified_planning.model import Problem

        class FalseByDefaultProblem(Problem):
            @property
            def initial_values(self):  # type: ignore[override]
                return self.explicit_initial_values

            def clone(self):
                twin = super().clone()
                twin.__class__ = FalseByDefaultProblem
                return twin

        _PROBLEM = FalseByDefaultProblem
    return _PROBLEM


def _not(x: Any) -> Any:
    from unified_planning.shortcuts import Not
    return Not(x)


_UNSAFE = re.compile(r"[^A-Za-z0-9_\-:.]")
_OPERATOR_WORDS = {"=": "_", "!=": "_ne_", "<": "_lt_", "<=": "_le_", ">": "_gt_", ">=": "_ge_"}


def safe(name: str) -> str:
    """A name Unified Planning takes (letters, digits, _ - : .; anything else becomes _)."""
    return _UNSAFE.sub("_", name)


def build(skills: list[SkillSpec], world: World, goals: list[Goal]) -> Domain:
    """The planning problem of reaching `goals` in `world` with `skills`. GoalError names a
    goal that names an unknown predicate or element."""
    return _Builder(skills, world).build(goals)
