"""Property: a key with a list of values, as SkiROS2 has it (skiros2_common.core.property).
An element's properties are Properties; a skill parameter (skillbus.skill.params.Param)
is one too, with a stricter type check.

    >>> p = Property("skiros:Size", [0.1, 0.2])
    >>> p.value, p.values, p.isList(), p.dataType()
    (0.1, [0.1, 0.2], True, <class 'float'>)
    >>> p.setValue(0.3, -1)          # an index replaces (negative: from the end) ...
    >>> p.setValue(0.4, 5)           # ... one past the end appends
    >>> p.getValuesStr()
    '0.1;0.3;0.4'
    >>> p.setValuesFromStr("1;2.5")  # converted to the property's type
    >>> p.values, p.find(2.5), p.find(7.0)
    ([1.0, 2.5], 1, -1)
    >>> p.printState()
    'skiros:Size:[1.0, 2.5]'
"""

from __future__ import annotations

import copy

import ast
from typing import Any

PRINT_LIMIT = 500  # printState cuts the value list after this many characters (as SkiROS2)


_new_object = object.__new__
_IMMUTABLE = frozenset((str, int, float, bool))


class Property:
    """A key with a list of values of one type (``value`` is the first).

    A property made from a type (``Property("k", float)``) has that type and no values; one
    made from a list has the list's values (a copy: SkiROS2 keeps the caller's list object).
    An element's property takes a value of any type: the world model types each value on
    its own (SkiROS2 logs an error and drops a value whose type differs)."""

    def __init__(self, key: str, value: Any = None, is_list: bool = False) -> None:
        self._key = key
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
        p._key, p._values = key, values
        p._type = type(values[0]) if values else None
        return p

    def _copy(self) -> "Property":
        """A copy that shares nothing that can change, as copy.deepcopy but cheaper: the
        values the world model stores (str, int, float, bool) are immutable and shared;
        any other value is deep-copied."""
        cls = type(self)
        p = _new_object(cls)
        values = [v if type(v) in _IMMUTABLE else copy.deepcopy(v) for v in self._values]
        if cls is Property:  # (attributes set one by one: no instance dict is made)
            p._key, p._type, p._values = self._key, self._type, values
        else:
            p.__dict__.update(self.__dict__)
            p._values = values
        return p

    # -- what a subclass checks ------------------------------------------------------
    def _check(self, v: Any) -> None:
        """Raises TypeError when `v` may not be stored (any value may, here; a Param checks
        its type)."""

    def _changed(self) -> None:
        """Called after every change of the values (a Param notes the time)."""

    def _adopt_type(self) -> None:
        if self._values and self._type is None:
            self._type = type(self._values[0])

    # -- SkiROS2's API ---------------------------------------------------------------
    @property
    def key(self) -> str:
        return self._key

    @key.setter
    def key(self, k: str) -> None:
        self._key = k

    def dataType(self) -> type | None:
        return self._type

    def dataTypeIs(self, t: Any) -> bool:
        """With a type: is it the property's type (exactly)? With a value: is it an instance
        of the property's type? (SkiROS2 code often passes an instance: ``dataTypeIs(Element())``.)"""
        if isinstance(t, type):
            return self._type is t
        return self._type is not None and isinstance(t, self._type)

    def makeInstance(self) -> Any:
        """A new value of the property's type, made with no arguments (``float()`` is 0.0)."""
        if self._type is None:
            raise TypeError(f"property {self._key} has no type yet")
        return self._type()

    def isSpecified(self) -> bool:
        return bool(self._values)

    def isList(self) -> bool:
        return len(self._values) > 1

    @property
    def value(self) -> Any:
        return self.getValue()

    @value.setter
    def value(self, v: Any) -> None:
        self.setValue(v)

    @property
    def values(self) -> list:
        return self.getValues()

    @values.setter
    def values(self, v: Any) -> None:
        self.setValues(v)

    def getValue(self, index: int = 0) -> Any:
        """The value at `index`, None when there is none (SkiROS2 raises IndexError past the
        end of a non-empty list; so does this)."""
        return self._values[index] if self._values else None

    def getValues(self) -> list:
        """The value list itself (not a copy, as in SkiROS2: editing it edits the property)."""
        return self._values

    def setValue(self, v: Any, index: int = 0) -> None:
        """Replaces the value at `index` (negative counts from the end); an index past the
        end appends."""
        self._check(v)
        if index < len(self._values):
            self._values[index] = v
        else:
            self._values.append(v)
        self._adopt_type()
        self._changed()

    def setValues(self, v: Any) -> None:
        """None clears the values, a list (or tuple) replaces them, a single value makes
        the list of that value."""
        values = [] if v is None else self._as_list(v)
        for x in values:
            self._check(x)
        self._values = values
        self._adopt_type()
        self._changed()

    def addValue(self, v: Any) -> None:
        self._check(v)
        self._values.append(v)
        self._adopt_type()
        self._changed()

    def append(self, v: Any) -> None:
        self.addValue(v)

    def removeValue(self, v: Any) -> None:
        """Removes the first value equal to `v`; nothing if there is none."""
        i = self.find(v)
        if i >= 0:
            del self._values[i]
            self._changed()

    def find(self, v: Any) -> int:
        """The index of the first value equal to `v`, or -1."""
        for i, x in enumerate(self._values):
            if x == v:
                return i
        return -1

    def unset(self) -> None:
        """Removes every value (the type stays): ``value`` is None afterwards."""
        self._values = []
        self._changed()

    def getValuesStr(self) -> str:
        return ";".join(str(v) for v in self._values)

    def setValueFromStr(self, text: str, index: int = 0) -> None:
        """Sets the value at `index` from text: a dict property reads a Python literal, any
        other type is called with the text (``float("2.5")``); a property without a type
        stores the text."""
        if self._type is dict:
            v = ast.literal_eval(text)
        elif self._type is bool:
            v = _bool_from_str(text)  # bool("False") would be True
        elif self._type is not None:
            v = self._type(text)
        else:
            v = text
        self.setValue(v, index)

    def setValuesFromStr(self, text: str) -> None:
        """Replaces the values by the ``;``-separated ones in `text` (see setValueFromStr)."""
        self.unset()
        for i, token in enumerate(text.split(";")):
            self.setValueFromStr(token, i)

    def printState(self) -> str:
        v = str(self._values)
        return f"{self._key}:{v}" if len(v) < PRINT_LIMIT else f"{self._key}:{v[:PRINT_LIMIT]} ...]"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Property) and (self._key, self._values) == (other._key, other._values)

    __hash__ = None  # type: ignore[assignment]  # mutable, compared by value

    def __repr__(self) -> str:
        return f"{self._key}: {self._values}"


def _bool_from_str(text: str) -> bool:
    t = text.strip().lower()
    if t in ("true", "1", "yes"):
        return True
    if t in ("false", "0", "no", ""):
        return False
    raise ValueError(f"not a boolean: {text!r}")
