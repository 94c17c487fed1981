"""The parameters of a skill (SkiROS2's skiros2_common.core.params.ParamHandler): a map
from key to Param, in the order they were added.

As in SkiROS2, a key that is not there is no exception for the lookups (``ph[key]``,
getParam, getParamValue, getParamValues) and the setters (specify, specifyDefault): they
log an error and give None or do nothing. setDefault and isSpecified raise KeyError.

    >>> ph = ParamHandler()
    >>> ph.addParam("Trajectory", dict, ParamTypes.Required)
    >>> ph.printState()
    'Trajectory:[] '
    >>> ph.specify("Trajectory", {"MyTraj": "Ue"})
    >>> ph.printState()
    "Trajectory:[{'MyTraj': 'Ue'}] "
    >>> ph.setDefault("Trajectory")
    >>> ph.printState()
    'Trajectory:[] '
"""

from __future__ import annotations

import copy
import logging
from typing import Any, ItemsView, Iterator, KeysView, ValuesView

from skillbus.skill.param import Param, ParamTypes
from skillbus.world.element import Element

log = logging.getLogger("skillbus.params")


class ParamHandler:
    """``ParamHandler(params=None)``: `params` is a dict key -> Param, used as it is."""

    def __init__(self, params: dict[str, Param] | None = None) -> None:
        self._params: dict[str, Param] = params if params else {}

    # -- the map ---------------------------------------------------------------------------
    def __getitem__(self, key: str) -> Param | None:
        return self._get(key, "[]")

    def __contains__(self, key: str) -> bool:
        return key in self._params

    def __iter__(self) -> Iterator[str]:
        return iter(self._params)

    def __len__(self) -> int:
        return len(self._params)

    def keys(self) -> KeysView[str]:
        return self._params.keys()

    def values(self) -> ValuesView[Param]:
        return self._params.values()

    def items(self) -> ItemsView[str, Param]:
        return self._params.items()

    def hasParam(self, key: str) -> bool:
        return key in self._params

    def getParamMap(self) -> dict[str, Param]:
        return self._params

    def reset(self, params: dict[str, Param]) -> None:
        """Takes `params` (a dict key -> Param, e.g. from getCopy or merge) as the map."""
        self._params = params

    def getCopy(self) -> dict[str, Param]:
        """A copy of the map, Params and values included: changing it leaves this handler
        alone (SkiROS2's copies share the value lists with the original)."""
        return {k: p.copy() for k, p in self._params.items()}

    def _get(self, key: str, caller: str) -> Param | None:
        p = self._params.get(key)
        if p is None:
            log.error("%s: parameter %r is not in the map (have: %s)", caller, key, self.printState())
        return p

    # -- adding and reading ------------------------------------------------------------------
    def addParam(self, key: str, value: Any, param_type: ParamTypes | int, options: list | str | None = None,
                 description: str = "") -> None:
        """Adds (or replaces) the parameter `key`. SkiROS2's ParamHandler takes the
        description fourth: a string there is taken as the description."""
        if isinstance(options, str):
            options, description = None, options
        self._params[key] = Param(key, description, value, param_type, options)

    def getParam(self, key: str) -> Param | None:
        return self._get(key, "getParam")

    def getParamValue(self, key: str) -> Any:
        """The first value, None when there is none (or no such parameter)."""
        p = self._get(key, "getParamValue")
        return None if p is None else p.getValue()

    def getParamValues(self, key: str) -> list | None:
        """The values ([] when there are none; None when there is no such parameter)."""
        p = self._get(key, "getParamValues")
        return None if p is None else p.getValues()

    def isSpecified(self, key: str) -> bool:
        return self._params[key].isSpecified()

    def getElementParams(self) -> dict[str, Param]:
        """The parameters whose (first) value is an element."""
        return {k: p for k, p in self._params.items() if isinstance(p.value, Element)}

    def getParamMapFiltered(self, type_filter: ParamTypes | list[ParamTypes]) -> dict[str, Param]:
        """The parameters of one kind, or of any kind in a list."""
        kinds = type_filter if isinstance(type_filter, list) else [type_filter]
        return {k: p for k, p in self._params.items() if p.paramType in kinds}

    # -- setting ---------------------------------------------------------------------------------
    def specify(self, key: str, values: Any) -> None:
        """Sets the values (a value or a list, as Param.setValues)."""
        p = self._get(key, "specify")
        if p is not None:
            p.setValues(values)

    def specifyDefault(self, key: str, values: Any) -> None:
        """Sets the values and makes them the default."""
        p = self._get(key, "specifyDefault")
        if p is not None:
            p.makeDefault(values)

    def setDefault(self, key: str | list[str] | None = None) -> None:
        """Resets a parameter, a list of them, or (None) all to their defaults."""
        keys = list(self._params) if key is None else key if isinstance(key, list) else [key]
        for k in keys:
            self._params[k].setDefault()

    def remap(self, initial_key: str, target_key: str) -> None:
        """Renames a parameter (nothing if there is none by `initial_key`); the Param's key
        follows (SkiROS2 leaves the Param's own key as it was)."""
        if initial_key in self._params:
            p = self._params.pop(initial_key)
            p.key = target_key
            self._params[target_key] = p

    def specifyParams(self, other: "ParamHandler", keep_default: bool = False) -> None:
        """Takes the values of the parameters `other` has too (others are ignored). With
        `keep_default`, a parameter with a default keeps it, except an element parameter
        whose default is abstract or names the same elements."""
        for key, theirs in other.items():
            mine = self._params.get(key)
            if mine is None:
                continue
            if keep_default and mine.hasSpecifiedDefault():
                if mine.dataTypeIs(Element) and (mine.getDefaultValue().isAbstract()
                                                 or _id_numbers(mine.getDefaultValues()) == _id_numbers(theirs.values)):
                    _take(mine, theirs.values, "specifyParams")
            else:
                _take(mine, theirs.values, "specifyParams")

    def specifyParamsDefault(self, other: "ParamHandler") -> None:
        """Takes the values of the parameters `other` has too, as defaults."""
        for key, theirs in other.items():
            if key in self._params:
                _take(self._params[key], theirs.values, "specifyParamsDefault", make_default=True)

    def merge(self, other: "ParamHandler") -> dict[str, Param]:
        """A new map (a dict, as SkiROS2's): a copy of this one where `other`'s parameters
        win: one with values sets them (or is added), one without values removes the key."""
        out = self.getCopy()
        for key, theirs in other.items():
            if key in out:
                if not theirs.values:
                    del out[key]
                else:
                    _take(out[key], copy.deepcopy(theirs.values), "merge")
            elif theirs.values:
                out[key] = copy.deepcopy(theirs)
        return out

    # -- text ------------------------------------------------------------------------------------
    def printState(self) -> str:
        """``"key:[values] "`` for each parameter; an element parameter with a value
        ``"key: <element> "``."""
        out = ""
        for p in self._params.values():
            if p.dataTypeIs(Element) and p.values:
                out += f"{p.key}: {p.value.printState()} "
            else:
                out += p.printState() + " "
        return out

    def __repr__(self) -> str:
        return f"ParamHandler({self.printState().strip()})"


def _take(p: Param, values: list, caller: str, make_default: bool = False) -> None:
    """Sets `p`'s values to a new list of `values` (the values themselves are shared, as in
    an assignment); one of another type is refused with a logged error, as in SkiROS2."""
    try:
        if make_default:
            p.makeDefault(list(values))
        else:
            p.setValues(list(values))
    except TypeError as e:
        log.error("%s: %s", caller, e)


def _id_numbers(values: list) -> set[int]:
    return {v.getIdNumber() for v in values if isinstance(v, Element)}
