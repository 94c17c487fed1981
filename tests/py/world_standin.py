"""A small in-memory world model for unit tests: the part of
skillbus.world.WorldModelInterface that conditions and Element.isInstance use, over a
dict of elements, a set of relations and a toy ontology (no bus, no server)."""

from __future__ import annotations

import copy

from skillbus.world import Element


class WorldStandIn:
    def __init__(self, superclasses: dict[str, str] | None = None, superproperties: dict[str, str] | None = None,
                 may_relate: set[tuple[str, str, str]] | None = None) -> None:
        self.elements: dict[str, Element] = {}
        self.relations: set[tuple[str, str, str]] = set()
        self.superclasses = superclasses or {}          # concept -> its parent
        self.superproperties = superproperties or {}    # predicate -> its parent
        self.abstract = may_relate or set()             # (concept, predicate, concept) the ontology allows
        self.next_id = 1

    # -- the toy ontology ------------------------------------------------------------
    def _up(self, name: str, parents: dict[str, str]) -> list[str]:
        out = [name]
        while out[-1] in parents:
            out.append(parents[out[-1]])
        return out

    def is_subclass(self, concept: str, ancestor: str) -> bool:
        return ancestor in self._up(concept, self.superclasses)

    def is_subproperty(self, pred: str, ancestor: str) -> bool:
        return ancestor in self._up(pred, self.superproperties)

    # -- what the world model interface offers -----------------------------------------------
    def add(self, etype: str, label: str = "", **properties) -> Element:
        """Test set-up: an element with properties (keyword: skiros_X -> skiros:X)."""
        e = Element(etype, label, f"{etype}-{self.next_id}")
        self.next_id += 1
        for k, v in properties.items():
            e.setProperty(k.replace("_", ":", 1), v)
        self.elements[e.id] = e
        return self.get_element(e.id)

    def has_element(self, eid: str) -> bool:
        return eid in self.elements

    def get_element(self, eid: str) -> Element:
        e = copy.deepcopy(self.elements[eid])
        for (s, p, o) in sorted(self.relations):
            if eid in (s, o):
                e.addRelation(s, p, o)
        e.mark_loaded()
        return e

    def get_relations(self, subj: str = "", pred: str = "", obj: str = "") -> list[dict]:
        subj, obj = ("" if subj == "-1" else subj), ("" if obj == "-1" else obj)
        return [{"src": s, "type": p, "dst": o, "state": True, "abstract": False} for (s, p, o) in sorted(self.relations)
                if subj in ("", s) and pred in ("", p) and obj in ("", o)]

    def has_relation(self, subj: str, pred: str, obj: str) -> bool:
        subj, obj = ("" if subj == "-1" else subj), ("" if obj == "-1" else obj)
        return any(subj in ("", s) and obj in ("", o) and (not pred or self.is_subproperty(p, pred))
                   for (s, p, o) in self.relations)

    def is_instance_of(self, eid: str, concept: str) -> bool:
        return eid in self.elements and self.is_subclass(self.elements[eid].type, concept)

    def may_relate(self, subject_concept: str, pred: str, object_concept: str) -> bool:
        return any(self.is_subclass(subject_concept, c) and self.is_subproperty(q, pred)
                   and self.is_subclass(object_concept, d) for (c, q, d) in self.abstract)

    def set_relation(self, subj: str, pred: str, obj: str, value: bool = True) -> None:
        (self.relations.add if value else self.relations.discard)((subj, pred, obj))

    def update_element(self, e: Element) -> Element:
        stored = copy.deepcopy(e)
        stored._relations = []
        self.elements[e.id] = stored
        return self.get_element(e.id)

    def add_element(self, e: Element) -> Element:
        if e.isAbstract():
            e._id = f"{e.type}-{self.next_id}"
            self.next_id += 1
        return self.update_element(e)

    def remove_element(self, e: Element | str) -> None:
        eid = e if isinstance(e, str) else e.id
        del self.elements[eid]
        self.relations = {r for r in self.relations if eid not in (r[0], r[2])}
