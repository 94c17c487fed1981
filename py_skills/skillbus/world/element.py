"""Element and Property with SkiROS2's API (skiros2_common.core.world_element), so that
skill code ports by changing imports.

    >>> e = Element("skiros:Cube", "red")
    >>> e.setProperty("skiros:Size", 0.05)
    >>> e.getProperty("skiros:Size").value
    0.05
    >>> e.addRelation("-1", "skiros:at", "skiros:Table-1")
    >>> e.getRelations(pred="skiros:at")
    [{'src': '-1', 'type': 'skiros:at', 'dst': 'skiros:Table-1', 'state': True, 'abstract': False}]
"""

from __future__ import annotations

import logging
from typing import Any, Iterable

from skillbus.world import element_data
from skillbus.world.property import Property

log = logging.getLogger("skillbus.world")

_DATATYPES = {"xsd:double": float, "xsd:float": float, "xsd:int": int, "xsd:integer": int,
              "xsd:boolean": bool, "xsd:string": str}


_new_object = object.__new__


def _copy_properties(props: dict[str, Property]) -> dict[str, Property]:
    """The properties, each with a list of values of its own (values are immutable)."""
    return {k: p._copy() for k, p in props.items()}


class Element:
    """A world-model element: type (a concept), label, id (empty while abstract),
    properties and relations. ``"-1"`` as a relation's subject or object means this element."""

    def __init__(self, etype: str = "Unknown", elabel: str = "", eid: str = "") -> None:
        self._type, self._label, self._id = etype, elabel, eid
        self._properties: dict[str, Property] = {}
        self._relations: list[dict] = []
        # What the element carried when it was read from the world model (or received as
        # a parameter): an update writes only what changed since (see mark_loaded).
        self._loaded: tuple[str, str, dict[str, Property], frozenset] | None = None

    @classmethod
    def _from_wire(cls, etype: str, label: str, eid: str, properties: dict[str, "Property"]) -> "Element":
        """An element read off the wire (skillbus.world.wire), without the checks and
        copies of building one by hand: a replica of 100,000 elements makes as many."""
        e = cls.__new__(cls)
        e._type, e._label, e._id = etype, label, eid
        e._properties, e._relations, e._loaded = properties, [], None
        return e

    _property_from_wire = staticmethod(Property._from_wire)

    @classmethod
    def _reader_copy(cls, src: "Element", relations: tuple) -> "Element":
        """A copy of a replica's element for a reader, paid for as it is read: a property is
        copied from `src`'s when getProperty first returns it (hasProperty reads `src`'s),
        all of them when anything else first touches them, its relation dicts are made
        from `relations` ((s, p, o), sorted) when first touched, and what it was loaded as
        (mark_loaded) when first asked. `src`'s properties may be shared until then because
        the replica never changes an element in place (a change replaces it)."""
        e = _new_object(cls)
        e.__dict__.update(_type=src._type, _label=src._label, _id=src._id,
                          _shared=(src._properties, relations, src._type, src._label))
        return e

    def __getattr__(self, name: str) -> Any:
        # Called only for an attribute not set: the parts of a reader copy not made yet.
        shared = self.__dict__.get("_shared")
        if shared is not None:
            if name == "_properties":  # (keeping those getProperty has handed out already)
                handed = self.__dict__.pop("_handed", {})
                value: Any = {k: handed.get(k) or p._copy() for k, p in shared[0].items()}
            elif name == "_relations":
                value = [{"src": s, "type": p, "dst": o, "state": True, "abstract": False} for (s, p, o) in shared[1]]
            elif name == "_loaded":
                value = (shared[2], shared[3], shared[0], frozenset(shared[1]))
            else:
                raise AttributeError(name)
            self.__dict__[name] = value
            return value
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    # -- identity ---------------------------------------------------------
    @property
    def id(self) -> str:
        return self._id

    @property
    def type(self) -> str:
        return self._type

    @type.setter
    def type(self, t: str) -> None:
        self._type = t

    @property
    def label(self) -> str:
        return self._label

    @label.setter
    def label(self, label: str) -> None:
        self._label = label

    def isAbstract(self) -> bool:
        return self._id == ""

    def getIdNumber(self) -> int:
        """The number at the end of the id (``skiros:Cube-3`` gives 3); -1 without one
        (an abstract element). SkiROS2 reads the part after the first ``-`` and raises on
        an id like ``a:b-c-2``; the number after the last one is the same for every id the
        world model gives."""
        _, dash, number = self._id.rpartition("-")
        return int(number) if dash and number.isdigit() else -1

    def setUri(self, eid: Any) -> None:
        self._id = f"{self._type}-{eid}"

    def printState(self, verbose: bool = False, filter: str = "") -> str:
        out = (self._id or self._type) + "-" + self._label
        if verbose:
            out += "".join(f"\n{p.printState()}" for k, p in self._properties.items() if filter in ("", k))
            out += "".join(f"\n{r}" for r in self._relations)
        return out

    def __repr__(self) -> str:
        return self.printState()

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Element) and (self._id, self._type, self._label) == (other._id, other._type, other._label)
                and self._properties == other._properties
                and sorted(map(_rel_key, self._relations)) == sorted(map(_rel_key, other._relations)))

    __hash__ = None  # type: ignore[assignment]  # mutable, compared by value

    def clone(self) -> "Element":
        """A copy that shares nothing that can change (as copy.deepcopy, at a fraction of
        its cost: values are immutable, so each property copies its list only)."""
        e = _new_object(type(self))
        d = e.__dict__
        props = self._properties  # (a reader copy's: all copied now)
        d.update(self.__dict__)  # (what it was loaded as is never changed in place: shared)
        d["_properties"] = _copy_properties(props)
        d["_relations"] = [dict(r) for r in self._relations]
        return e

    def mark_loaded(self, resolved: frozenset | None = None) -> None:
        """Remembers type, label, properties and relations as they are now: what the world
        model holds. ``WorldModelInterface.update_element`` then writes only the
        differences, so a property or relation this copy never carried is never erased.
        `resolved`: its relations as (subject, predicate, object) with its own id for
        "-1", when the caller has them already (they are not read back from the dicts)."""
        self._loaded = (self._type, self._label, _copy_properties(self._properties),
                        frozenset(self._resolved_relations()) if resolved is None else resolved)

    def loaded(self) -> tuple[str, str, dict[str, Property], frozenset] | None:
        """What it was loaded as (type, label, properties, relations), or None: to read,
        never to change (a reader copy shares it with the element it was copied from)."""
        return self._loaded

    def changed_since_loaded(self) -> bool:
        """Whether type, label, properties or relations differ from what it carried when
        it was read (True for an element made by hand)."""
        if self._loaded is None:
            return True
        etype, label, props, rels = self._loaded
        return ((self._type, self._label) != (etype, label) or self._properties != props
                or frozenset(self._resolved_relations()) != rels)

    # -- properties -------------------------------------------------------
    @property
    def available_properties(self):
        """The property keys (a view, as in SkiROS2)."""
        return self._properties.keys()

    @property
    def properties(self) -> list[Property]:
        return list(self._properties.values())

    def _wire_properties(self) -> list[Property]:
        """The properties as ``properties`` lists them, to be read and never changed: a
        reader copy's are not copied for it (those getProperty handed out are its own, the
        rest still the replica's). Encoders use it: every tick sends the skill's elements."""
        props = self._unread()
        if props is None:
            return list(self._properties.values())
        handed = self.__dict__.get("_handed") or {}
        return [handed.get(k) or p for k, p in props.items()]

    def _unread(self) -> dict[str, Property] | None:
        """A reader copy whose properties are not all copied yet: the replica's (to read,
        never to hand out); else None."""
        d = self.__dict__
        return d["_shared"][0] if "_properties" not in d and "_shared" in d else None

    def hasProperty(self, key: str, value: Any = None, not_none: bool = False) -> bool:
        """Whether the element has the property; with `value`, whether that is among its
        values; with `not_none`, whether it has a value at all."""
        props = self._unread()
        if props is not None:
            handed = self.__dict__.get("_handed")
            p = (handed or {}).get(key) or props.get(key)
        else:
            p = self._properties.get(key)
        if p is None:
            return False
        if value is not None:
            return p.find(value) != -1
        return not not_none or p.isSpecified()

    def getProperty(self, key: str) -> Property:
        props = self._unread()
        if props is not None and key in props:  # a reader copy: copy this one only
            handed = self.__dict__.setdefault("_handed", {})
            p = handed.get(key)
            if p is None:
                p = handed[key] = props[key]._copy()
            return p
        if key not in self._properties:
            raise KeyError(f"{self.printState()} has no property {key}")
        return self._properties[key]

    def setProperty(self, key: str, value: Any, datatype: str | None = None, force_convertion: bool = False,
                    *, is_list: bool = False) -> None:
        """Sets the property's values (a list sets several). With `datatype` (an xsd type)
        the property is made anew with that type and the value converted to it (SkiROS2
        leaves it empty unless the value has the type already); with `force_convertion`
        the value is converted to the existing property's type. A type as the value makes
        an empty property of that type."""
        if datatype:
            if datatype not in _DATATYPES:
                raise ValueError(f"datatype {datatype} is not one of {sorted(_DATATYPES)}")
            conv = _DATATYPES[datatype]
            prop = Property(key, conv)
            if value is not None and not isinstance(value, type):
                prop.setValues([conv(v) for v in Property._as_list(value)])
            self._properties[key] = prop
        elif key in self._properties:
            prop = self._properties[key]
            if force_convertion and prop.dataType() is not None:
                value = [prop.dataType()(v) for v in Property._as_list(value)]
            prop.setValues(value)
        else:
            self._properties[key] = Property(key, value)

    def appendProperty(self, key: str, value: Any) -> None:
        """Adds a value to the property, making it if it is missing."""
        if key in self._properties:
            self._properties[key].addValue(value)
        else:
            self.setProperty(key, value)

    def removeProperty(self, key: str) -> None:
        del self._properties[key]

    # -- data codes (SkiROS2's spatial reasoner; see skillbus.world.element_data) ----
    def hasData(self, code: str) -> bool:
        return element_data.has_data(self, code)

    def getData(self, code: str) -> Any:
        return element_data.get_data(self, code)

    def setData(self, code: str, data: Any) -> None:
        element_data.set_data(self, code, data)

    # -- relations --------------------------------------------------------
    # A relation is a dict {src, type, dst, state, abstract}. "-1" as src or dst stands for
    # this element (SkiROS2's convention); an element read from the world model carries
    # its own id there instead. Lookups take either form for either: getRelations(subj="-1")
    # finds the element's outgoing relations whichever way they are written.
    def _is_me(self, end: str) -> bool:
        return end == "-1" or (end != "" and end == self._id)

    def _same_end(self, stored: str, asked: str) -> bool:
        return stored == asked or (self._is_me(asked) and self._is_me(stored))

    def _end_matches(self, stored: str, asked: str) -> bool:
        return asked == "" or self._same_end(stored, asked)

    def getRelations(self, subj: str = "", pred: str | Iterable[str] = (), obj: str = "") -> list[dict]:
        """The relations (the stored dicts themselves, in order) matching the filters: "" is
        any; `pred` may be a list (any of them); "-1" or the element's id is this element."""
        preds = [pred] if isinstance(pred, str) else list(pred)
        preds = [] if preds and preds[0] == "" else preds
        return [r for r in self._relations
                if self._end_matches(r["src"], subj) and (not preds or r["type"] in preds)
                and self._end_matches(r["dst"], obj)]

    def getRelation(self, subj: str = "", pred: str | Iterable[str] = (), obj: str = "") -> dict | None:
        """The first relation getRelations finds, or None."""
        found = self.getRelations(subj, pred, obj)
        return found[0] if found else None

    def addRelation(self, subj: Any, predicate: str, obj: Any, value: bool = True, abstract: bool = False) -> None:
        subj = subj.id if isinstance(subj, Element) else subj
        obj = obj.id if isinstance(obj, Element) else obj
        if not isinstance(subj, str) or not isinstance(obj, str):
            raise ValueError(f"relation subject and object must be ids, got {type(subj).__name__} and "
                             f"{type(obj).__name__}")
        rel = {"src": subj, "type": predicate, "dst": obj, "state": value, "abstract": abstract}
        if rel not in self._relations:  # (a scan: fine for a few; the replica builds its copies without it)
            self._relations.append(rel)

    def setRelation(self, subj: str, predicate: str, obj: str) -> None:
        """Sets the relation, removing earlier ones of this predicate from the same side."""
        self.removeRelations(self.getRelations(subj if subj == "-1" else "", predicate, obj if obj == "-1" else ""))
        self.addRelation(subj, predicate, obj)

    def hasRelation(self, subj: str, predicate: str, obj: str, value: bool = True, abstract: bool = False) -> bool:
        """True if the element has the relation; "-1" (in it or in the query) is this element."""
        want = _rel_key({"src": subj, "type": predicate, "dst": obj}, self._id or "-1")
        return any(_rel_key(r, self._id or "-1") == want and r["state"] == value and r["abstract"] == abstract
                   for r in self._relations)

    def removeRelation(self, relation: dict) -> None:
        self._relations.remove(relation)

    def removeRelations(self, relations: Iterable[dict]) -> None:
        for r in list(relations):
            self.removeRelation(r)

    def removeRelation2(self, subj: str, predicate: str, obj: str, value: bool = True, abstract: bool = False) -> None:
        """Removes the relation given by its parts ("-1" or the id: this element); logs an
        error (as SkiROS2) when the element has no such relation."""
        for r in self._relations:
            if (r["type"] == predicate and r["state"] == value and r["abstract"] == abstract
                    and self._same_end(r["src"], subj) and self._same_end(r["dst"], obj)):
                self._relations.remove(r)
                return
        log.error("removeRelation2: %s has no relation %s-%s-%s (state %s, abstract %s)", self.printState(), subj,
                  predicate, obj, value, abstract)

    def isInstance(self, abstract: "Element", wmi: Any) -> bool:
        """Whether this element fits the abstract description `abstract`: its type or a
        subclass, its label unless that is "" or "Unknown", every value of its
        properties, and its relations (with "-1" standing for the element) as the world
        model `wmi` has them (a subproperty of a relation counts)."""
        if self._type != abstract.type and not (self._id and wmi.is_instance_of(self._id, abstract.type)):
            return False
        if abstract.label not in ("", "Unknown") and abstract.label != self._label:
            return False
        for key, p in abstract._properties.items():
            if not self.hasProperty(key) or any(v not in self.getProperty(key).values for v in p.values):
                return False
        for r in abstract._relations:
            if r["src"] in ("-1", abstract.id):
                ok = wmi.has_relation(self._id, r["type"], "")
            else:
                ok = wmi.has_relation("", r["type"], self._id)
            if not ok:
                return False
        return True

    def _resolved_relations(self) -> list[tuple[str, str, str]]:
        """Relations with "-1" replaced by this element's id (only true, concrete ones)."""
        return sorted({_rel_key(r, self._id) for r in self._relations if r["state"] and not r["abstract"]})


def _rel_key(r: dict, own_id: str = "") -> tuple[str, str, str]:
    s = own_id if r["src"] == "-1" and own_id else r["src"]
    o = own_id if r["dst"] == "-1" and own_id else r["dst"]
    return (s, r["type"], o)
