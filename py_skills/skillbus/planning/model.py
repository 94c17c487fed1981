"""The skills and the world as the planner sees them: plain data, read from the skill
manager's list (skill_description_t) and the world model's replica, or built in code (the
tests, the benchmark)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Iterable

from skillbus.world.ontology_view import OntologyView


@dataclass(frozen=True)
class Condition:
    kind: str            # Relation, AbstractRelation, HasProperty, Property, OnType, IsSpecified, Generate
    subject: str         # parameter keys
    object: str = ""
    owl: str = ""        # the relation, property or concept
    op: str = "="        # Property
    value: Any = None    # Property: the value compared with
    desired: bool = True
    or_label: str = ""   # members of one ConditionOr share it


@dataclass
class SkillSpec:
    type: str
    label: str
    params: list[tuple[str, str]]          # element parameters the planner binds: (key, concept), in order
    pre: list[Condition] = field(default_factory=list)
    post: list[Condition] = field(default_factory=list)
    hold: list[Condition] = field(default_factory=list)
    for_planning: bool = True              # False: the skill asked to be left out (SkiROS2's available_for_planning)

    @property
    def name(self) -> str:
        """The action's name: the implementation's label (unique in a manager)."""
        return self.label


@dataclass
class World:
    """Elements (id -> type and properties), relations (subject, predicate, object) and
    the ontology's hierarchy."""
    types: dict[str, str]
    properties: dict[str, dict[str, list[Any]]]
    relations: set[tuple[str, str, str]]
    ontology: OntologyView
    # (subject class, relation, object class) -> whether the ontology lets them relate:
    # what an AbstractConditionRelation asks (the world model client's may_relate)
    may_relate: Callable[[str, str, str], bool] | None = None

    def is_a(self, eid: str, concept: str) -> bool:
        t = self.types.get(eid)
        return t is not None and (t == concept or self.ontology.is_below("classes", t, concept))


def skill_from_msg(d: Any) -> SkillSpec:
    """A skill_description_t (the manager's list) as the planner sees it: its required
    element parameters and the optional ones a condition names (the inferred Robot, and an
    optional one no condition names, are the manager's to fill), its conditions."""
    from skillbus.msgs import skill_param_t
    from skillbus.skill.convert import value_from_msg
    def conds(cs: Iterable[Any]) -> list[Condition]:
        return [Condition(c.kind, c.subject, c.object, c.owl, c.op or "=", value_from_msg(c.value), bool(c.desired_state),
                          c.or_label) for c in cs]
    pre, post, hold = conds(d.pre), conds(d.post), conds(d.hold)
    # An optional element parameter no condition names is not the planner's to bind: bound,
    # it made the skill need such an element in the world and picked one at random.
    named = {k for c in pre + post + hold for k in (c.subject, c.object) if k}
    params = [(p.key, p.concept) for p in d.params
              if p.data_type == "element" and (p.param_type == skill_param_t.REQUIRED or
                                                (p.param_type == skill_param_t.OPTIONAL and p.key in named))]
    return SkillSpec(d.type, d.label, params, pre, post, hold, not bool(getattr(d, "not_for_planning", False)))


def world_from_client(wmi: Any) -> World:
    """The world as the replica shows it now."""
    types: dict[str, str] = {}
    props: dict[str, dict[str, list[Any]]] = {}
    for e in wmi.get_elements():
        types[e.id] = e.type
        props[e.id] = {p.key: list(p.values) for p in e.properties if p.values}
    relations = {(r["src"], r["type"], r["dst"]) for r in wmi.get_relations()}
    return World(types, props, relations, wmi.ontology_view(), wmi.may_relate)
