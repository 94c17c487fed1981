"""SkiROS2's ontology and world questions on the world-model client (its
OntologyInterface and WorldModelInterface method names), answered from the replica and
the world model server's queries (wm.query).

The server answers SPARQL (world/sparql.py) but changes no ontology; so:

* ``get_sub_classes`` and ``get_sub_properties`` name the class (property) itself and
  those of its subclasses (subproperties) that the world *uses*: the types of its
  elements, the predicates of its relations (the server says which are below). That is
  what code that filters the world's elements or relations by them needs.
* ``query_ontology`` is SPARQL on the server (world/sparql.py).
* ``get_super_class``, ``add_class``, ``get_template_element`` (the
  ontology's individuals), ``lock`` / ``unlock`` raise NotImplementedError saying why.
* There are no reasoner plug-ins: ``get_reasoner`` is None for every predicate.
"""

from __future__ import annotations

import copy
from typing import Any

from skillbus.msgs import wm_query_t
from skillbus.world.convert import relation_msg
from skillbus.world.element import Element

# SkiROS2's default relation filter of get_branch: its super-property of every relation
# between things of a scene. skillbus's ontology has no such property: where the server
# does not know it, every relation counts but skiros:hasTemplate (SkiROS2 files that one
# under skiros:conditionProperty, not under skiros:sceneProperty).
SCENE_PROPERTY = "skiros:sceneProperty"
NOT_IN_SCENE = frozenset({"skiros:hasTemplate"})

NO_ONTOLOGY_LIST = "the world model server has no RPC that lists its ontology (wm.query answers about elements)"


class SkiROS2Queries:
    """Mixed into WorldModelInterface (which provides the replica, query and get_element)."""

    _elements: dict[str, Element]
    _relations: set[tuple[str, str, str]]
    _by_node: dict[str, set[tuple[str, str, str]]]
    _subproperty_cache: dict[tuple[str, str], bool]

    # -- classes and individuals -----------------------------------------------------------
    def _of_type(self, concept: str, exact: bool = False) -> list[Element] | None:
        """The world's elements of `concept` (with its subclasses unless `exact`); None if
        the server does not know the concept."""
        from skillbus.world.client import WorldModelError
        q = wm_query_t()
        q.type, q.exact_type, q.ids_only = concept, exact, True
        try:
            return self.query(q)
        except WorldModelError:
            return None

    def get_individuals(self, parent_class: str, recursive: bool = True) -> list[str]:
        """The ids of the world's elements of `parent_class` (with its subclasses if
        `recursive`). The server keeps no individuals in its ontology: these are all."""
        return [e.id for e in self._of_type(parent_class, exact=not recursive) or []]

    def get_type(self, uri: str) -> list[str]:
        """The type of element `uri`, as a list ([]: no such element)."""
        self._fresh()
        e = self._elements.get(uri)
        return [e.type] if e is not None else []

    def get_types(self, uri: str) -> list[str]:
        """The ids of the elements whose type is exactly `uri`."""
        return [e.id for e in self._of_type(uri, exact=True) or []]

    def get_sub_classes(self, parent_class: str, recursive: bool = True) -> list[str]:
        """`parent_class` and those of its subclasses that elements of the world have ([]
        if the server does not know the class). See the module's docstring."""
        if not recursive:
            raise NotImplementedError(f"get_sub_classes(recursive=False): {NO_ONTOLOGY_LIST}, so the direct "
                                      f"subclasses cannot be told from the others")
        found = self._of_type(parent_class)
        if found is None:
            return []
        return [parent_class] + sorted({e.type for e in found} - {parent_class})

    def get_super_class(self, child_class: str) -> str:
        raise NotImplementedError(f"get_super_class({child_class!r}): {NO_ONTOLOGY_LIST}")

    # -- relation types ----------------------------------------------------------------------
    def get_sub_properties(self, parent_property: str, recursive: bool = True) -> list[str]:
        """`parent_property` and those of its subproperties that relations of the world
        use (the server says which predicates are below it). See the module's docstring."""
        if not recursive:
            raise NotImplementedError(f"get_sub_properties(recursive=False): {NO_ONTOLOGY_LIST}, so the direct "
                                      f"subproperties cannot be told from the others")
        self._fresh()
        used = sorted({p for (_, p, _) in self._relations} - {parent_property})
        return [parent_property] + [p for p in used if self.is_subproperty(p, parent_property)]

    def is_subproperty(self, pred: str, ancestor: str) -> bool:
        """Whether relation type `pred` is `ancestor` or below it, for a `pred` the world
        uses (the server is asked with one relation of that type as the witness)."""
        if pred == ancestor:
            return True
        key = (pred, ancestor)
        if key not in self._subproperty_cache:
            self._fresh()
            witness = _witness(self._relations, self._by_node, pred)
            if witness is None:
                return False  # not used in the world: no relation to ask about
            s, _, o = witness
            q = wm_query_t()
            q.ids, q.num_ids = [s], 1
            q.relations, q.num_relations = [relation_msg("", ancestor, o)], 1
            q.ids_only = True
            self._subproperty_cache[key] = bool(self.query(q))
        return self._subproperty_cache[key]

    def _predicates_under(self, relation_filter: str) -> set[str]:
        """The predicates of the world that `relation_filter` covers ("": all)."""
        self._fresh()
        used = {p for (_, p, _) in self._relations}
        if not relation_filter:
            return used
        below = {p for p in used if self.is_subproperty(p, relation_filter)}
        if not below and relation_filter == SCENE_PROPERTY:
            return used - NOT_IN_SCENE
        return below

    # -- the world -------------------------------------------------------------------------------
    def get_triples(self, subj: str | None = None, pred: str | None = None, obj: str | None = None) -> list[str]:
        """The world's triples that match (None or "" is any): the relations, each
        element's rdf:type, rdfs:label and property values. Each answer row holds the
        terms that were not given, as SkiROS2's query answers: one term as it is, more
        terms each followed by a space."""
        self._fresh()
        rows: list[str] = []
        for triple in self._triples():
            if any(given and given != term for given, term in zip((subj, pred, obj), triple)):
                continue
            free = [term for given, term in zip((subj, pred, obj), triple) if not given]
            rows.append(free[0] if len(free) == 1 else "".join(t + " " for t in free))
        return rows

    def _triples(self):
        for eid, e in sorted(self._elements.items()):
            yield (eid, "rdf:type", e.type)
            if e.label:
                yield (eid, "rdfs:label", e.label)
            for p in e.properties:
                for v in p.values:
                    yield (eid, p.key, str(v))
        yield from sorted(self._relations)

    def get_branch(self, eid: str, relation_filter: str = SCENE_PROPERTY, type_filter: str = "",
                   context_id: str = "scene") -> list[Element]:
        """The element `eid` and, depth first, every element reached from it through
        relations of `relation_filter` (or below it) whose type is `type_filter` (or below
        it; "" any), each once."""
        root = self.get_element(eid)
        preds = self._predicates_under(relation_filter)
        out: list[Element] = []
        seen = {eid}

        def visit(e: Element) -> None:
            out.append(e)
            for (s, p, o) in sorted(self._by_node.get(e.id, ())):
                if s != e.id or p not in preds or o in seen or o not in self._elements:
                    continue
                if type_filter and not self.is_instance_of(o, type_filter):
                    continue
                seen.add(o)
                visit(self.get_element(o))

        visit(root)
        return out

    def check_relation(self, subj: Element, pred: str, obj: Element, state: bool, abstract: bool) -> bool:
        """Whether `subj` `pred` `obj` holding is `state`. Abstract: between the elements'
        templates (their skiros:Template property, else their ids) in the world's
        triples; else in the world, a subproperty of `pred` counting."""
        if abstract:
            s = subj.getProperty("skiros:Template").value if subj.hasProperty("skiros:Template") else subj.id
            o = obj.getProperty("skiros:Template").value if obj.hasProperty("skiros:Template") else obj.id
            return (o in self.get_triples(s, pred)) == state
        return self.has_relation(subj.id, pred, obj.id) == state

    # -- templates -------------------------------------------------------------------------------
    def get_template_element(self, uri: str, context_id: str = "scene") -> Element:
        raise NotImplementedError(f"get_template_element({uri!r}): the world model server keeps no individuals "
                                  f"of its ontology (it reads classes, relation types and restrictions only); "
                                  f"build the Element and pass it to instanciate() or add_element()")

    def instanciate(self, uri: str | Element, recursive: bool = False, relations: list | None = None,
                    relation_filter: list | None = None, antiloop_bind: set | None = None,
                    context_id: str = "scene") -> Element:
        """Adds an element made from a template, with `relations` instead of the
        template's, and returns it. The template must be an Element (the server keeps no
        template individuals: get_template_element). `recursive` would instanciate the
        templates the relations name, which needs those individuals too."""
        template = self.get_template_element(uri) if isinstance(uri, str) else copy.deepcopy(uri)
        if recursive:
            filters = ["skiros:hasA", "skiros:contain"] if relation_filter is None else relation_filter
            if any(r["src"] == "-1" and (not filters or r["type"] in filters) for r in template.getRelations()):
                raise NotImplementedError("instanciate(recursive=True): the templates its relations name are "
                                          "individuals of the ontology, which the world model server does not keep")
        template._relations = [dict(r) for r in (relations or [])]
        template._id = ""
        return self.add_element(template)

    # -- reasoners, locking, the ontology itself --------------------------------------------------
    def get_reasoner(self, pred: str) -> Any:
        """The reasoner plug-in for a predicate or data code: skillbus has none (None, as
        SkiROS2 answers for a predicate without one)."""
        return None

    def get_reasoner_relations(self, subj: Element, pred: str, obj: Element) -> list | None:
        """None: no reasoner computes `pred` (skillbus has no reasoner plug-ins)."""
        return None

    def lock(self) -> bool:
        raise NotImplementedError("lock(): the world model server has no lock; a transaction that must see the "
                                  "world unchanged passes expected_version to commit() and is refused otherwise")

    def unlock(self) -> bool:
        raise NotImplementedError("unlock(): the world model server has no lock (see lock())")

    def add_class(self, class_uri: str, parent_uri: str, context: str = "") -> bool:
        raise NotImplementedError(f"add_class({class_uri!r}, {parent_uri!r}): the world model server cannot add "
                                  f"ontology classes while it runs (its ontology comes from its --ontology files, "
                                  f"and from the class axioms of a scene that `skillbus wm load` replaces the "
                                  f"world with)")



def _witness(relations: set, by_node: dict, pred: str) -> tuple[str, str, str] | None:
    """A relation of type `pred` whose two ends have no other relation between them, so
    that a question about "some relation between them below X" is about this one (else
    any relation of that type)."""
    first = None
    for (s, p, o) in sorted(relations):
        if p != pred:
            continue
        first = first or (s, p, o)
        if all(r == (s, p, o) for r in by_node.get(s, ()) if r[0] == s and r[2] == o):
            return (s, p, o)
    return first
