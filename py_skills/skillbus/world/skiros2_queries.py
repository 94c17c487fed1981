"""SkiROS2's ontology and world questions on the world-model client (its
OntologyInterface and WorldModelInterface method names), answered from the replica and the
server's ontology (world/ontology_view.py: the class and relation-type hierarchy the
server judges by, and the ontology's individuals, SkiROS2's templates, read once per
replica):

* ``get_sub_classes``, ``get_super_class``, ``get_sub_properties``, ``is_subproperty``:
  the hierarchy; ``get_individuals``, ``get_type(s)``: the world's elements and the
  ontology's individuals.
* ``get_template_element`` builds an Element from an individual of the ontology;
  ``instanciate`` adds one (and, recursive, those its relations name).
* ``add_class`` adds a class while the server runs (RPC wm.add_axioms); ``lock`` /
  ``unlock`` are the server's advisory lock (wm.lock); ``query_ontology`` is SPARQL
  (world/sparql.py).
* There are no reasoner plug-ins: ``get_reasoner`` is None for every predicate.
"""

from __future__ import annotations

import copy
import logging
import time
from typing import Any

from skillbus.msgs import wm_lock_t, wm_scene_t
from skillbus.world.element import Element
from skillbus.world.ontology_view import OntologyView

log = logging.getLogger("skillbus.world")

# SkiROS2's default relation filter of get_branch: its super-property of every relation
# between things of a scene. skillbus's ontology has no such property: where the server
# does not know it, every relation counts but skiros:hasTemplate (SkiROS2 files that one
# under skiros:conditionProperty, not under skiros:sceneProperty).
SCENE_PROPERTY = "skiros:sceneProperty"
NOT_IN_SCENE = frozenset({"skiros:hasTemplate"})


def _literal(text: str, datatype: str) -> Any:
    """A literal of the ontology as the Python value a Property holds."""
    if datatype in ("xsd:int", "xsd:integer", "xsd:long", "xsd:short"):
        return int(text)
    if datatype in ("xsd:double", "xsd:float", "xsd:decimal"):
        return float(text)
    if datatype == "xsd:boolean":
        return text.strip().lower() in ("true", "1")
    return text


class SkiROS2Queries:
    """Mixed into WorldModelInterface (which provides the replica, query and get_element)."""

    _elements: dict[str, Element]
    _relations: set[tuple[str, str, str]]
    _by_node: dict[str, set[tuple[str, str, str]]]
    _ontology_cache: OntologyView | None

    # -- the ontology ------------------------------------------------------------------------------
    def ontology_view(self) -> OntologyView:
        """The server's class and relation-type hierarchy and its ontology's individuals,
        read once and kept until the replica reads the world again (RPC wm.hierarchy)."""
        self._fresh()  # (a reset, another client's add_class or scene load, drops it)
        if self._ontology_cache is None:
            rep = self._call("hierarchy", wm_scene_t(), wm_scene_t)  # type: ignore[attr-defined]
            self._ontology_cache = OntologyView.from_json(rep.turtle)
        return self._ontology_cache

    # -- classes and individuals -----------------------------------------------------------
    def get_individuals(self, parent_class: str, recursive: bool = True) -> list[str]:
        """The world's elements and the ontology's individuals (templates) of
        `parent_class` (with its subclasses if `recursive`), sorted."""
        view = self.ontology_view()
        types = set(view.below("classes", parent_class) if recursive else [parent_class])
        self._fresh()
        found = {eid for eid, e in self._elements.items() if e.type in types}
        found |= {iri for iri in view.individuals if types & set(view.types_of_individual(iri))}
        return sorted(found)

    def get_type(self, uri: str) -> list[str]:
        """The type of element `uri`, or the rdf:type statements of individual `uri` of the
        ontology (with owl:NamedIndividual, as SkiROS2 answers); [] for neither."""
        self._fresh()
        e = self._elements.get(uri)
        if e is not None:
            return [e.type]
        return self.ontology_view().types_of_individual(uri)

    def get_types(self, uri: str) -> list[str]:
        """The ids of the elements, and the ontology's individuals, whose type is exactly `uri`."""
        self._fresh()
        view = self.ontology_view()
        return sorted({eid for eid, e in self._elements.items() if e.type == uri} |
                      {iri for iri in view.individuals if uri in view.types_of_individual(iri)})

    def get_sub_classes(self, parent_class: str, recursive: bool = True) -> list[str]:
        """Recursive: `parent_class` and every class below it (SkiROS2's
        ``rdfs:subClassOf*``), `parent_class` first; else its direct subclasses. [] for a
        class the server's ontology does not know."""
        view = self.ontology_view()
        return view.below("classes", parent_class) if recursive else view.children("classes", parent_class)

    def get_super_class(self, child_class: str) -> str:
        """The direct superclass of `child_class` (the first by name when there are
        several). A class with none (or unknown) logs an error and raises IndexError, as
        SkiROS2's does."""
        parents = self.ontology_view().parents("classes", child_class)
        if not parents:
            why = "has no superclass" if self.ontology_view().knows("classes", child_class) else \
                "is no class of the world model's ontology"
            log.error("[get_super_class] %s %s", child_class, why)
            raise IndexError(f"get_super_class: {child_class} {why}")
        return parents[0]

    def is_subclass(self, concept: str, ancestor: str) -> bool:
        """Whether class `concept` is `ancestor` or below it in the server's ontology."""
        return concept == ancestor or self.ontology_view().is_below("classes", concept, ancestor)

    # -- relation types ----------------------------------------------------------------------
    def get_sub_properties(self, parent_property: str, recursive: bool = True) -> list[str]:
        """Recursive: `parent_property` and every relation type below it (SkiROS2's
        ``rdfs:subPropertyOf*``), `parent_property` first; else its direct subproperties.
        [] for a relation type the server's ontology does not know."""
        view = self.ontology_view()
        return view.below("relations", parent_property) if recursive else view.children("relations", parent_property)

    def is_subproperty(self, pred: str, ancestor: str) -> bool:
        """Whether relation type `pred` is `ancestor` or below it in the server's ontology."""
        return pred == ancestor or self.ontology_view().is_below("relations", pred, ancestor)

    def _predicates_under(self, relation_filter: str) -> set[str]:
        """The predicates of the world that `relation_filter` covers ("": all)."""
        self._fresh()
        used = {p for (_, p, _) in self._relations}
        if not relation_filter:
            return used
        if relation_filter == SCENE_PROPERTY and not self.ontology_view().knows("relations", SCENE_PROPERTY):
            return used - NOT_IN_SCENE
        return {p for p in used if self.is_subproperty(p, relation_filter)}

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
        """An Element made from individual `uri` of the ontology (not in the world): its
        type, its literals as properties, its relations to other IRIs (subject "-1"), the
        relations of the ontology's other individuals to it (object "-1", but
        skiros:hasTemplate), label `uri` and the property skiros:Template `uri`, as
        SkiROS2's. Raises WorldModelError for an IRI that is no individual."""
        from skillbus.world.client import WorldModelError
        view = self.ontology_view()
        rows = view.individuals.get(uri)
        if rows is None:
            raise WorldModelError(f"get_template_element: {uri} is no individual (owl:NamedIndividual) of the world "
                                  f"model's ontology")
        e = Element()
        for pred, obj, datatype, _lang in rows:
            if pred == "rdf:type":
                if obj != "owl:NamedIndividual":
                    e._type = obj
            elif pred == "rdfs:label" and datatype:
                e._label = obj
            elif datatype:
                e.appendProperty(pred, _literal(obj, datatype))
            else:
                e.addRelation("-1", pred, obj)
        for other, other_rows in sorted(view.individuals.items()):
            for pred, obj, datatype, _lang in other_rows:
                if not datatype and obj == uri and pred != "skiros:hasTemplate":
                    e.addRelation(other, pred, "-1")
        e._label = uri
        e.setProperty("skiros:Template", uri)
        return e

    def instanciate(self, uri: str | Element, recursive: bool = False, relations: list | None = None,
                    relation_filter: list | None = None, antiloop_bind: set | None = None,
                    context_id: str = "scene") -> Element:
        """Adds an element made from a template (an individual's IRI, or an Element) with
        `relations` instead of the template's, and returns it. `recursive`: each template
        its relations of `relation_filter` (default skiros:hasA, skiros:contain; [] any)
        name from it is instanciated too, related to the new element so; a template is
        instanciated once per call (a loop of templates ends)."""
        template = self.get_template_element(uri) if isinstance(uri, str) else copy.deepcopy(uri)
        filters = ["skiros:hasA", "skiros:contain"] if relation_filter is None else relation_filter
        seen = set() if antiloop_bind is None else antiloop_bind
        if template.hasProperty("skiros:Template"):
            seen.add(template.getProperty("skiros:Template").value)
        own = [dict(r) for r in template.getRelations()]
        template._relations = [dict(r) for r in (relations or [])]
        template._id = ""
        added = self.add_element(template)
        if recursive:
            for r in own:
                if r["src"] != "-1" or (filters and r["type"] not in filters) or r["dst"] in seen:
                    continue
                link = dict(r, src=added.id, dst="-1")
                child = self.instanciate(r["dst"], True, [link], filters, seen, context_id)
                added.addRelation("-1", r["type"], child.id)
        return added

    # -- reasoners, locking, the ontology itself --------------------------------------------------
    def get_reasoner(self, pred: str) -> Any:
        """The reasoner plug-in for a predicate or data code: skillbus has none (None, as
        SkiROS2 answers for a predicate without one)."""
        return None

    def get_reasoner_relations(self, subj: Element, pred: str, obj: Element) -> list | None:
        """None: no reasoner computes `pred` (skillbus has no reasoner plug-ins)."""
        return None

    def lock(self, timeout: float | None = 60.0) -> bool:
        """Takes the world model server's advisory lock, waiting while another client
        holds it (SkiROS2's lock: nothing else waits for it; clients that want exclusive
        access agree to take it). True once taken (taking it again is fine); TimeoutError
        naming the holder after `timeout` seconds (None: wait for ever, as SkiROS2). A
        server restart frees it."""
        deadline = None if timeout is None else time.monotonic() + timeout
        req = wm_lock_t()
        req.holder, req.lock = self.rpc.client_id, True  # type: ignore[attr-defined]
        while True:
            rep = self._call("lock", req, wm_lock_t)  # type: ignore[attr-defined]
            if rep.ok:
                return True
            if deadline is not None and time.monotonic() >= deadline:
                raise TimeoutError(f"lock: the world model is still locked by {rep.holder} after {timeout} s")
            time.sleep(0.05)

    def unlock(self) -> bool:
        """Frees the advisory lock, whoever holds it (as SkiROS2's: so a holder that died
        blocks no one for ever); False when it was not locked."""
        req = wm_lock_t()
        req.holder, req.lock = self.rpc.client_id, False  # type: ignore[attr-defined]
        return bool(self._call("lock", req, wm_lock_t).ok)  # type: ignore[attr-defined]

    def add_class(self, class_uri: str, parent_uri: str, context: str = "") -> bool:
        """Adds class `class_uri` below `parent_uri` (a class the ontology knows) to the
        world model's ontology while it runs: it is kept with the loaded scene's axioms
        (a save carries it, a restart keeps it; the next scene load replaces it, as the
        scene's own), and every replica, the skill manager's too, reads the world again
        with it. True; raises WorldModelError naming what is wrong (SkiROS2 returns False)."""
        from skillbus.world.client import WorldModelError
        view = self.ontology_view()
        if not view.knows("classes", parent_uri):
            raise WorldModelError(f"add_class({class_uri!r}): {parent_uri} is no class of the world model's ontology")
        if parent_uri in view.parents("classes", class_uri):
            return True
        req = wm_scene_t()
        req.turtle = f"{_term(class_uri)} a owl:Class ; rdfs:subClassOf {_term(parent_uri)} .\n"
        rep = self._call("add_axioms", req, wm_scene_t)  # type: ignore[attr-defined]
        self._ontology_cache = None
        self.sync(rep.version)  # type: ignore[attr-defined]
        return True


def _term(name: str) -> str:
    """A class name as Turtle: a full IRI in <>, a prefixed name as it is."""
    if "://" in name:
        return name if name.startswith("<") else f"<{name}>"
    if ":" not in name or any(c.isspace() for c in name):
        raise ValueError(f"{name!r} is no prefixed name (prefix:Name) or IRI")
    return name
