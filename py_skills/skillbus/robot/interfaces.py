"""The robot interfaces of a skill process, loaded by name from its configuration.

A skill reaches hardware only through a named interface (``interfaces.get("arm")``);
which module implements it is configuration, not code, so the simulated robot (the
physics server) and a real robot's drivers are two implementations that skills cannot
tell apart::

    skillbus skills-process --name skills --library my_skills \\
        --interface arm=skillbus.robot.arm \\
        --interface gripper=skillbus.can.gripper_service:gripper0:5

or the same in the process's configuration file (``--config skills.toml``)::

    [interfaces]
    arm = "skillbus.robot.arm"
    gripper = "skillbus.can.gripper_service:gripper0:5"

(``--arm`` and ``--gripper CHANNEL[:NODE]`` are shortcuts for these two.) An interface
module has ``interface(bus, participant, arg, **options) -> object``: ``arg`` is the text
after the module's name and a colon ("" without one); ``participant`` is the process's
lockstep participant or None on the wall clock.

    >>> parse("gripper=skillbus.can.gripper_service:gripper0:5")
    ('gripper', 'skillbus.can.gripper_service', 'gripper0:5')
"""

from __future__ import annotations

import importlib
from typing import Any


class InterfaceError(RuntimeError):
    """An interface that is not configured, or that could not be set up; says which."""


_loaded: dict[str, Any] = {}
_how: dict[str, str] = {}  # name -> "module[:arg]", for messages


def parse(text: str) -> tuple[str, str, str]:
    """``NAME=MODULE[:ARG]`` -> (name, module, arg)."""
    name, eq, rest = text.partition("=")
    module, _, arg = rest.partition(":")
    if not eq or not name or not module:
        raise InterfaceError(f"--interface {text!r}: expected NAME=MODULE[:ARG], e.g. arm=skillbus.robot.arm")
    return name, module, arg


def load(name: str, module: str, arg: str, bus: Any, participant: Any = None, **options: Any) -> Any:
    """Imports `module`, calls its ``interface(bus, participant, arg, **options)`` and keeps
    the result as interface `name`."""
    try:
        mod = importlib.import_module(module)
    except ImportError as e:
        raise InterfaceError(f"interface {name}: cannot import {module}: {e}") from None
    make = getattr(mod, "interface", None)
    if not callable(make):
        raise InterfaceError(f"interface {name}: {module} has no interface(bus, participant, arg) function")
    _loaded[name] = make(bus, participant, arg, **options)
    _how[name] = module + (f":{arg}" if arg else "")
    return _loaded[name]


def get(name: str, hint: str = "") -> Any:
    """The interface `name`; raises InterfaceError naming what this process has."""
    if name not in _loaded:
        have = ", ".join(f"{n}={h}" for n, h in sorted(_how.items())) or "none"
        raise InterfaceError(f"this skill process has no {name} interface (it has: {have}); "
                             f"configure one with --interface {name}=MODULE[:ARG]" + (f" or {hint}" if hint else ""))
    return _loaded[name]


def configured() -> dict[str, str]:
    return dict(_how)


def forget(name: str) -> None:
    _loaded.pop(name, None)
    _how.pop(name, None)
