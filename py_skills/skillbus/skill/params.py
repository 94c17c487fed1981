"""Skill parameters, as SkiROS2 has them (skiros2_common.core.params).

A parameter has a key, a value (a type such as ``float``, a concrete value, or an
``Element`` of a concept), a kind (``ParamTypes``) and a description::

    >>> p = Param("Speed", "how fast", 0.5, ParamTypes.Optional)
    >>> p.value, p.dataType(), p.isSpecified()
    (0.5, <class 'float'>, True)
    >>> q = Param("Object", "", Element("skiros:Product"), ParamTypes.Inferred)
    >>> q.dataTypeIs(Element), q.value.type
    (True, 'skiros:Product')
"""

from __future__ import annotations

import copy
import enum
from typing import Any, Iterator

from skillbus.msgs import skill_param_t
from skillbus.world.element import Element


class ParamTypes(enum.IntEnum):
    """Required: must have a value when the skill starts; with a value in the description
    it is static (overwrites the blackboard each run). Optional: may stay empty; a value in
    the description is a default, used when the blackboard has none. Inferred: a required
    element that pre-conditions may fill in from the world model."""
    Required = skill_param_t.REQUIRED  # the numbers are the IDL's (lcmtypes/skill_param_t.lcm)
    Optional = skill_param_t.OPTIONAL
    Inferred = skill_param_t.INFERRED


_TYPES = (int, float, str, bool, list, dict, Element)


class Param:
    def __init__(self, key: str, description: str, value: Any, param_type: ParamTypes,
                 options: list | None = None) -> None:
        if not isinstance(param_type, ParamTypes):
            param_type = ParamTypes(param_type)
        self.key, self.description, self.paramType = key, description, param_type
        self.options = list(options or [])
        if isinstance(value, type):
            if value not in _TYPES:
                raise TypeError(f"parameter {key}: type {value.__name__} is not one of "
                                f"{', '.join(t.__name__ for t in _TYPES)}")
            self._type, self._values = value, []
        elif isinstance(value, Element):
            self._type, self._values = Element, [value]
        else:
            if not isinstance(value, _TYPES[:-1]):
                raise TypeError(f"parameter {key}: a value of type {type(value).__name__} is not supported")
            self._type, self._values = type(value), [value]
        self._default = copy.deepcopy(self._values)

    # -- values -------------------------------------------------------------
    @property
    def value(self) -> Any:
        return self._values[0] if self._values else None

    @value.setter
    def value(self, v: Any) -> None:
        self._check(v)
        self._values = [v]

    @property
    def values(self) -> list:
        return self._values

    @values.setter
    def values(self, vs: Any) -> None:
        self.setValues(vs)

    def setValues(self, vs: Any) -> None:
        vs = list(vs) if isinstance(vs, (list, tuple)) and self._type is not list else [vs]
        for v in vs:
            self._check(v)
        self._values = vs

    def setValue(self, v: Any, index: int = 0) -> None:
        self._check(v)
        self._values[index] = v

    def addValue(self, v: Any) -> None:
        self._check(v)
        self._values.append(v)

    def getValue(self, index: int = 0) -> Any:
        return self._values[index] if len(self._values) > index else None

    def getValues(self) -> list:
        return self._values

    def _check(self, v: Any) -> None:
        ok = isinstance(v, self._type) or (self._type is float and isinstance(v, int) and not isinstance(v, bool))
        if not ok:
            raise TypeError(f"parameter {self.key} holds {self._type.__name__}, not {type(v).__name__} ({v!r})")

    def isSpecified(self) -> bool:
        if not self._values:
            return False
        if self._type is Element:
            return all(not v.isAbstract() for v in self._values)
        return True

    def dataType(self) -> type:
        return self._type

    def dataTypeIs(self, t: type) -> bool:
        return self._type is t

    def paramTypeIs(self, t: ParamTypes) -> bool:
        return self.paramType == t

    # -- defaults ------------------------------------------------------------
    def hasSpecifiedDefault(self) -> bool:
        return bool(self._default) and (self._type is not Element or not self._default[0].isAbstract())

    def getDefaultValue(self, index: int = 0) -> Any:
        return self._default[index]

    def getDefaultValues(self) -> list:
        return self._default

    def setDefault(self) -> None:
        self._values = copy.deepcopy(self._default)

    def makeDefault(self, values: Any) -> None:
        self.setValues(values)
        self._default = copy.deepcopy(self._values)

    def __repr__(self) -> str:
        return f"{self.key}:{self._values}"


class ParamHandler:
    """The parameters of a skill: ``params["Key"].value``."""

    def __init__(self) -> None:
        self._params: dict[str, Param] = {}

    def __getitem__(self, key: str) -> Param:
        if key not in self._params:
            raise KeyError(f"no parameter {key!r} (have: {', '.join(self._params) or 'none'})")
        return self._params[key]

    def __contains__(self, key: str) -> bool:
        return key in self._params

    def __iter__(self) -> Iterator[str]:
        return iter(self._params)

    def items(self):
        return self._params.items()

    def hasParam(self, key: str) -> bool:
        return key in self._params

    def addParam(self, key: str, value: Any, param_type: ParamTypes, options: list | None = None,
                 description: str = "") -> None:
        self._params[key] = Param(key, description, value, param_type, options)

    def getParam(self, key: str) -> Param:
        return self[key]

    def getParamValue(self, key: str) -> Any:
        return self[key].value

    def getParamValues(self, key: str) -> list:
        return self[key].values

    def specify(self, key: str, values: Any) -> None:
        self[key].setValues(values)

    def specifyDefault(self, key: str, values: Any) -> None:
        self[key].makeDefault(values)

    def isSpecified(self, key: str) -> bool:
        return self[key].isSpecified()

    def remap(self, initial_key: str, target_key: str) -> None:
        if initial_key in self._params:
            p = self._params.pop(initial_key)
            p.key = target_key
            self._params[target_key] = p

    def getParamMap(self) -> dict[str, Param]:
        return self._params

    def getParamMapFiltered(self, param_type: ParamTypes | list[ParamTypes]) -> dict[str, Param]:
        types = param_type if isinstance(param_type, list) else [param_type]
        return {k: p for k, p in self._params.items() if p.paramType in types}

    def getCopy(self) -> dict[str, Param]:
        return copy.deepcopy(self._params)

    def printState(self) -> str:
        return " ".join(repr(p) for p in self._params.values())
