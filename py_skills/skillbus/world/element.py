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

import copy
from typing import Any, Iterable

_DATATYPES = {"xsd:double": float, "xsd:float": float, "xsd:int": int, "xsd:integer": int,
              "xsd:boolean": bool, "xsd:string": str}


class Property:
    """A key with a list of values of one type (``value`` is the first)."""

    def __init__(self, key: str, value: Any = None, is_list: bool = False) -> None:
        self.key = key
        self._type: type | None = value if isinstance(value, type) else None
        self._values: list = [] if value is None or isinstance(value, type) else self._as_list(value)
        if self._values and self._type is None:
            self._type = type(self._values[0])

    @staticmethod
    def _as_list(v: Any) -> list:
        return list(v) if isinstance(v, (list, tuple)) else [v]

    @classmethod
    def _from_wire(cls, key: str, values: list) -> "Property":
        """A property read off the wire (skillbus.world.wire): `values` taken as they are."""
        p = cls.__new__(cls)
        p.key, p._values = key, values
        p._type = type(values[0]) if values else None
        return p

    def dataType(self) -> type | None:
        return self._type

    @property
    def value(self) -> Any:
        return self._values[0] if self._values else None

    @value.setter
    def value(self, v: Any) -> None:
        self.setValues(v)

    @property
    def values(self) -> list:
        return self._values

    @values.setter
    def values(self, v: Any) -> None:
        self.setValues(v)

    def setValues(self, v: Any) -> None:
        self._values = self._as_list(v)
        if self._values and self._type is None:
            self._type = type(self._values[0])

    def setValue(self, v: Any, index: int = 0) -> None:
        self._values[index] = v

    def append(self, v: Any) -> None:
        self._values.append(v)

    def find(self, v: Any) -> int:
        return self._values.index(v) if v in self._values else -1

    def isSpecified(self) -> bool:
        return bool(self._values)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Property) and (self.key, self._values) == (other.key, other._values)

    def __repr__(self) -> str:
        return f"{self.key}: {self._values}"


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
        return int(self._id.rsplit("-", 1)[1]) if "-" in self._id else -1

    def setUri(self, eid: Any) -> None:
        self._id = f"{self._type}-{eid}"

    def printState(self, verbose: bool = False, filter: str = "") -> str:
        out = (self._id or self._type) + "-" + self._label
        if verbose:
            out += "".join(f"\n{p}" for k, p in self._properties.items() if filter in ("", k))
            out += "".join(f"\n{r}" for r in self._relations)
        return out

    def __repr__(self) -> str:
        return self.printState()

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, Element) and (self._id, self._type, self._label) == (other._id, other._type, other._label)
                and self._properties == other._properties
                and sorted(map(_rel_key, self._relations)) == sorted(map(_rel_key, other._relations)))

    def clone(self) -> "Element":
        return copy.deepcopy(self)

    def mark_loaded(self) -> None:
        """Remembers type, label, properties and relations as they are now: what the world
        model holds. ``WorldModelInterface.update_element`` then writes only the
        differences, so a property or relation this copy never carried is never erased."""
        self._loaded = (self._type, self._label, copy.deepcopy(self._properties),
                        frozenset(self._resolved_relations()))

    def loaded(self) -> tuple[str, str, dict[str, Property], frozenset] | None:
        return self._loaded

    # -- properties -------------------------------------------------------
    def available_properties(self) -> list[str]:
        return list(self._properties)

    @property
    def properties(self) -> list[Property]:
        return list(self._properties.values())

    def hasProperty(self, key: str, value: Any = None, not_none: bool = False) -> bool:
        if key not in self._properties:
            return False
        if value is not None:
            return self._properties[key].find(value) != -1
        return not not_none or self._properties[key].isSpecified()

    def getProperty(self, key: str) -> Property:
        if key not in self._properties:
            raise KeyError(f"{self.printState()} has no property {key}")
        return self._properties[key]

    def setProperty(self, key: str, value: Any, datatype: str | None = None, is_list: bool = False,
                    force_convertion: bool = False) -> None:
        if datatype:
            if datatype not in _DATATYPES:
                raise ValueError(f"datatype {datatype} is not one of {sorted(_DATATYPES)}")
            conv = _DATATYPES[datatype]
            prop = Property(key, conv)
            if value is not None:
                prop.setValues([conv(v) for v in Property._as_list(value)])
            self._properties[key] = prop
        elif key in self._properties:
            prop = self._properties[key]
            if force_convertion and prop.dataType() is not None:
                value = [prop.dataType()(v) for v in Property._as_list(value)]
            prop.setValues(value)
        else:
            self._properties[key] = Property(key, value, is_list)

    def appendProperty(self, key: str, value: Any) -> None:
        if key in self._properties:
            self._properties[key].append(value)
        else:
            self.setProperty(key, value, is_list=True)

    def removeProperty(self, key: str) -> None:
        del self._properties[key]

    # -- relations --------------------------------------------------------
    def getRelations(self, subj: str = "", pred: str | Iterable[str] = (), obj: str = "") -> list[dict]:
        preds = [pred] if isinstance(pred, str) else list(pred)
        preds = [] if preds and preds[0] == "" else preds
        return [r for r in self._relations
                if subj in ("", r["src"]) and (not preds or r["type"] in preds) and obj in ("", r["dst"])]

    def getRelation(self, subj: str = "", pred: str | Iterable[str] = (), obj: str = "") -> dict | None:
        found = self.getRelations(subj, pred, obj)
        return found[0] if found else None

    def addRelation(self, subj: Any, predicate: str, obj: Any, value: bool = True, abstract: bool = False) -> None:
        subj = subj.id if isinstance(subj, Element) else subj
        obj = obj.id if isinstance(obj, Element) else obj
        if not isinstance(subj, str) or not isinstance(obj, str):
            raise ValueError(f"relation subject and object must be ids, got {type(subj).__name__} and "
                             f"{type(obj).__name__}")
        rel = {"src": subj, "type": predicate, "dst": obj, "state": value, "abstract": abstract}
        if rel not in self._relations:
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

    def _resolved_relations(self) -> list[tuple[str, str, str]]:
        """Relations with "-1" replaced by this element's id (only true, concrete ones)."""
        return sorted({_rel_key(r, self._id) for r in self._relations if r["state"] and not r["abstract"]})


def _rel_key(r: dict, own_id: str = "") -> tuple[str, str, str]:
    s = own_id if r["src"] == "-1" and own_id else r["src"]
    o = own_id if r["dst"] == "-1" and own_id else r["dst"]
    return (s, r["type"], o)
