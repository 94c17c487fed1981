"""Parameter values from text (``skillbus run -p KEY=VALUE``), parsed strictly by the
parameter's data type; the skill manager parses ``--start KEY=VALUE`` by the same rules
(skill_mgr/src/param_check.cpp)::

    >>> parse_text("bool", "", "TRUE"), parse_text("int", "", "5"), parse_text("list", "", "[1, 2]")
    (True, 5, [1, 2])
    >>> parse_text("bool", "", "maybe")
    Traceback (most recent call last):
    ...
    ValueError: 'maybe' is not a bool (true, false, 1 or 0)
"""

from __future__ import annotations

import json
from typing import Any

from skillbus.world.element import Element

_BOOLS = {"true": True, "1": True, "false": False, "0": False}


def parse_text(data_type: str, concept: str, text: str) -> Any:
    """The value of `text` for a parameter of `data_type` (an element of `concept`).
    Raises ValueError saying why it is not one."""
    if data_type == "element":
        if not text:
            raise ValueError("an element id is needed (e.g. skiros:Cube-2)")
        return Element(concept or "Unknown", "", text)
    if data_type == "bool":
        if text.lower() not in _BOOLS:
            raise ValueError(f"{text!r} is not a bool (true, false, 1 or 0)")
        return _BOOLS[text.lower()]
    if data_type in ("int", "float"):
        try:
            return int(text) if data_type == "int" else float(text)
        except ValueError:
            raise ValueError(f"{text!r} is not a {data_type}") from None
    if data_type in ("list", "dict"):
        try:
            value = json.loads(text)
        except json.JSONDecodeError as e:
            raise ValueError(f"{text!r} is not JSON ({e})") from None
        if not isinstance(value, list if data_type == "list" else dict):
            raise ValueError(f"{text!r} is not a JSON {data_type}")
        return value
    if data_type == "str":
        return text
    raise ValueError(f"unknown data type {data_type!r}")
