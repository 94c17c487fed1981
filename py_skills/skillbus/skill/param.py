"""A skill parameter (SkiROS2's skiros2_common.core.params.Param): a Property with a kind
(``ParamTypes``), a description, defaults and the time of its last change.

    >>> p = Param("Speed", "how fast", 0.5, ParamTypes.Optional)
    >>> p.value, p.dataType(), p.isSpecified(), p.default
    (0.5, <class 'float'>, True, 0.5)
    >>> q = Param("Object", "", Element("skiros:Product"), ParamTypes.Inferred)
    >>> q.dataTypeIs(Element), q.value.type
    (True, 'skiros:Product')
    >>> r = Param("Via", "", [1.1, 2.0], ParamTypes.Required)   # a list: several values
    >>> r.values, r.value, r.isList()
    ([1.1, 2.0], 1.1, True)
"""

from __future__ import annotations

import copy
import enum
from datetime import datetime, timedelta
from typing import Any

from skillbus.msgs import skill_param_t
from skillbus.world.element import Element
from skillbus.world.property import Property


class ParamTypes(enum.IntEnum):
    """Required: must have a value when the skill starts; with a value in the description
    it is static (overwrites the blackboard each run). Optional: may stay empty; a value in
    the description is a default, used when the blackboard has none. Inferred: a required
    element that pre-conditions may fill in from the world model.

    The numbers are the IDL's (lcmtypes/skill_param_t.lcm), 0 to 2: SkiROS2's enum counts
    from 1 but serialises ``value - 1``, and ``Param(..., param_type=<int>)`` reads an int
    the same way in both."""
    Required = skill_param_t.REQUIRED
    Optional = skill_param_t.OPTIONAL
    Inferred = skill_param_t.INFERRED


TYPES = (int, float, str, bool, list, dict, Element)

# A change is dated at least this much after the previous one, so that hasChanges (which
# wants more than its 1 µs tolerance) sees two changes in a row, however fast they come.
_MIN_STEP = timedelta(microseconds=2)

_new_param = object.__new__
_IMMUTABLE = frozenset((str, int, float, bool, type(None)))


def copy_values(values: list) -> list:
    """A list of parameter values copied as copy.deepcopy would: immutable values shared,
    elements cloned (Element.clone), lists copied through, anything else deep-copied."""
    out = []
    for v in values:
        t = type(v)
        if t in _IMMUTABLE:
            out.append(v)
        elif t is Element:
            out.append(v.clone())
        elif t is list:
            out.append(copy_values(v))
        else:
            out.append(copy.deepcopy(v))
    return out


class Param(Property):
    """A parameter: ``Param(key, description, value, param_type)``. `value` is a type
    (no value yet), a value, or a list of values of one type. `options` lists the values
    the parameter may take (skillbus: shown by ``skillbus skills``, not enforced)."""

    def __init__(self, key: str, description: str, value: Any, param_type: ParamTypes | int,
                 options: list | None = None) -> None:
        self._key = key
        self.description = description
        self._param_type = param_type if isinstance(param_type, ParamTypes) else ParamTypes(param_type)
        self.options = list(options or [])
        self._type, self._values = _type_and_values(key, value)
        self._default = copy_values(self._values)
        self._last_update = datetime.now()

    def copy(self) -> "Param":
        """A copy that shares nothing that can change, as copy.deepcopy but several times
        cheaper (copy_values): every start of a primitive copies its description's
        parameters, inside the frame of its tick."""
        p = _new_param(type(self))
        p.__dict__.update(self.__dict__)
        p._values, p._default = copy_values(self._values), copy_values(self._default)
        p.options = copy_values(self.options)
        return p

    def __deepcopy__(self, memo: dict) -> "Param":
        return self.copy()

    # -- kind, description, time -------------------------------------------------------
    @property
    def paramType(self) -> ParamTypes:
        return self._param_type

    def paramTypeIs(self, param_type: ParamTypes) -> bool:
        return self._param_type == param_type

    @property
    def last_update(self) -> datetime:
        """When the values last changed (setValue, setValues, addValue, removeValue, unset)."""
        return self._last_update

    def hasChanges(self, time: datetime, tolerance: int = 1) -> bool:
        """Whether the values changed more than `tolerance` microseconds after `time`."""
        return self._last_update - time > timedelta(microseconds=tolerance)

    def _changed(self) -> None:
        self._last_update = max(datetime.now(), self._last_update + _MIN_STEP)

    # -- values ---------------------------------------------------------------------------
    def _check(self, v: Any) -> None:
        ok = isinstance(v, self._type) or (self._type is float and isinstance(v, int) and not isinstance(v, bool))
        if not ok:
            raise TypeError(f"parameter {self._key} holds {self._type.__name__}, not {type(v).__name__} ({v!r})")

    def setValues(self, v: Any) -> None:
        """None clears the values, a list replaces them, a single value makes the list of
        that value. A list-typed parameter takes a list of lists as its values and any
        other list as one value (``p.values = [1, 2]`` holds the list [1, 2])."""
        if self._type is list and isinstance(v, (list, tuple)) and not all(isinstance(x, list) for x in v):
            v = [list(v)]
        super().setValues(v)

    def isSpecified(self) -> bool:
        """Whether it has a value; an element parameter: a concrete one (with an id), every
        value (SkiROS2: any value, an abstract element too)."""
        if not self._values:
            return False
        if self._type is Element:
            return all(not v.isAbstract() for v in self._values)
        return True

    # -- defaults ----------------------------------------------------------------------------
    @property
    def default(self) -> Any:
        return self.getDefaultValue()

    @property
    def defaults(self) -> list:
        return self.getDefaultValues()

    def hasSpecifiedDefault(self) -> bool:
        return bool(self._default)

    def getDefaultValue(self, index: int = 0) -> Any:
        return self._default[index] if self._default else None

    def getDefaultValues(self) -> list:
        return self._default

    def hasDefaultValues(self) -> bool:
        """Whether the values are the defaults (all of them: SkiROS2 compares pairwise up
        to the shorter list, so no values count as the defaults)."""
        return self._values == self._default

    def setDefault(self) -> None:
        """Back to (a copy of) the defaults."""
        self._values = copy_values(self._default)

    def makeDefault(self, values: Any) -> None:
        """Sets the values (as setValues) and makes them the defaults."""
        self.setValues(values)
        self._default = copy_values(self._values)

    # -- as a world-model element -------------------------------------------------------------
    def toElement(self) -> Element:
        """The parameter as SkiROS2 describes it in the world model: a skiros:Parameter
        labelled with the key, with rdfs:comment, skiros:ParameterType (0..2) and
        skiros:DataType (an empty property of the Python type; for an element parameter the
        concept) and skiros:Default and skiros:Value (for an element parameter, a
        skiros:hasValue relation to each concrete value instead)."""
        e = Element("skiros:Parameter", self._key)
        e.setProperty("rdfs:comment", self.description)
        e.setProperty("skiros:ParameterType", int(self._param_type))
        if self._type is not Element:
            e.setProperty("skiros:DataType", self._type)
            if self._default:
                e.setProperty("skiros:Default", copy.deepcopy(self._default))
            if self._values:
                e.setProperty("skiros:Value", copy.deepcopy(self._values))
        else:
            concept = (self._default or self._values or [Element("")])[0].type
            e.setProperty("skiros:DataType", concept)
            for v in self._values:
                if not v.isAbstract():
                    e.addRelation("-1", "skiros:hasValue", v.id)
        return e

    def __repr__(self) -> str:
        return self.printState()


def _type_and_values(key: str, value: Any) -> tuple[type, list]:
    if isinstance(value, type):
        if value not in TYPES:
            raise TypeError(f"parameter {key}: type {value.__name__} is not one of "
                            f"{', '.join(t.__name__ for t in TYPES)}")
        return value, []
    if isinstance(value, list):
        if not value:
            raise ValueError(f"parameter {key}: an empty list has no type; give the type (e.g. float or list)")
        t = _type_of(key, value[0])
        probe = Param.__new__(Param)
        probe._key, probe._type = key, t
        for v in value:
            try:
                probe._check(v)
            except TypeError:
                raise ValueError(f"parameter {key}: all values must be of the same type ({value!r})") from None
        return t, list(value)
    return _type_of(key, value), [value]


def _type_of(key: str, value: Any) -> type:
    if isinstance(value, Element):
        return Element
    if not isinstance(value, TYPES[:-1]):
        raise TypeError(f"parameter {key}: a value of type {type(value).__name__} is not supported")
    return type(value)
