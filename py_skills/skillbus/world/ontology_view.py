"""The world model server's ontology as a client holds it: the class and relation-type
hierarchy the server judges by and the ontology's individuals (SkiROS2's templates),
read with one RPC (wm.hierarchy) and kept until the client reads the world again (a
scene load or a class added while the server runs makes every replica do so).

    >>> v = OntologyView.from_json({"classes": {"a:Thing": [], "a:Cup": ["a:Thing"],
    ...     "a:Mug": ["a:Cup"]}, "relations": {"a:near": [], "a:on": ["a:near"]},
    ...     "individuals": {}})
    >>> v.below("classes", "a:Thing"), v.children("classes", "a:Thing"), v.parents("classes", "a:Mug")
    (['a:Thing', 'a:Cup', 'a:Mug'], ['a:Cup'], ['a:Cup'])
    >>> v.is_below("relations", "a:on", "a:near"), v.is_below("relations", "a:near", "a:on")
    (True, False)
    >>> v.below("classes", "a:Unicorn")
    []
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Literal

Kind = Literal["classes", "relations"]

# One statement of an individual: predicate, object (an IRI compacted, or a literal's
# text), the literal's datatype ("" for an IRI) and language.
Statement = tuple[str, str, str, str]


@dataclass
class OntologyView:
    parents_of: dict[str, dict[str, frozenset[str]]]  # kind -> {name: direct parents}
    individuals: dict[str, list[Statement]]
    _children: dict[str, dict[str, list[str]]] = field(default_factory=dict)

    @classmethod
    def from_json(cls, data: dict | str) -> "OntologyView":
        d = json.loads(data) if isinstance(data, str) else data
        parents = {kind: {name: frozenset(ups) for name, ups in d.get(kind, {}).items()}
                   for kind in ("classes", "relations")}
        individuals = {iri: [tuple(s) for s in rows] for iri, rows in d.get("individuals", {}).items()}
        return cls(parents, individuals)  # type: ignore[arg-type]

    def knows(self, kind: Kind, name: str) -> bool:
        return name in self.parents_of[kind]

    def parents(self, kind: Kind, name: str) -> list[str]:
        return sorted(self.parents_of[kind].get(name, ()))

    def children(self, kind: Kind, name: str) -> list[str]:
        if kind not in self._children:
            index: dict[str, list[str]] = {}
            for child, ups in self.parents_of[kind].items():
                for up in ups:
                    index.setdefault(up, []).append(child)
            self._children[kind] = {k: sorted(v) for k, v in index.items()}
        return list(self._children[kind].get(name, ()))

    def below(self, kind: Kind, name: str) -> list[str]:
        """`name` first, then everything below it, each once, breadth first (by name at
        each level); [] when the ontology does not know `name`."""
        if not self.knows(kind, name):
            return []
        out, seen, level = [name], {name}, [name]
        while level:
            nxt = sorted({c for n in level for c in self.children(kind, n)} - seen)
            seen.update(nxt)
            out += nxt
            level = nxt
        return out

    def is_below(self, kind: Kind, name: str, ancestor: str) -> bool:
        """Whether `name` is `ancestor` or below it (reflexive, as the server's checks)."""
        if name == ancestor:
            return True
        todo, seen = [name], {name}
        while todo:
            for up in self.parents_of[kind].get(todo.pop(), ()):
                if up == ancestor:
                    return True
                if up not in seen:
                    seen.add(up)
                    todo.append(up)
        return False

    def types_of_individual(self, iri: str) -> list[str]:
        return [o for (p, o, dt, _lang) in self.individuals.get(iri, ()) if p == "rdf:type" and not dt]
