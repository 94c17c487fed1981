"""Processors, as a compound skill names them in expand(). Each is a description; the
skill manager's tree engine executes it (skill_mgr/src/tree/processors/, one per file,
registered by name in skill_mgr/src/tree/processor_registry.cpp; docs/processors.md has
the table and how to add one). A skill process checks these classes against the
manager's table when it registers (`all_processors()` here, the `processors` RPC there).

    >>> Loop(3).spec(), NoFail(Selector()).spec()
    ('Loop(3)', 'NoFail(Selector)')
"""

from __future__ import annotations


class Processor:
    def spec(self) -> str:
        return type(self).__name__

    def __repr__(self) -> str:
        return self.spec() + "()"


class Serial(Processor):
    pass


class SerialStar(Processor):
    pass


class Sequential(SerialStar):
    """Deprecated alias of SerialStar (SkiROS2's default processor)."""

    def spec(self) -> str:
        return "SerialStar"


class Selector(Processor):
    pass


class SelectorStar(Processor):
    pass


class ParallelFf(Processor):
    pass


class ParallelFs(Processor):
    pass


class _Counted(Processor):
    def __init__(self, n: int | None = None) -> None:
        if n is not None and (not isinstance(n, int) or n < 0):
            raise ValueError(f"{type(self).__name__}: n must be a non-negative int or None, got {n!r}")
        self.n = n

    def spec(self) -> str:
        return type(self).__name__ + ("" if self.n is None else f"({self.n})")


class Loop(_Counted):
    """Runs the children in sequence n times (forever without n)."""


class RetryOnFail(_Counted):
    """Runs the children in sequence; after a failure starts over, at most n more times."""


class NoFail(Processor):
    def __init__(self, processor: Processor | None = None) -> None:
        self.processor = processor or SerialStar()

    def spec(self) -> str:
        return f"NoFail({self.processor.spec()})"


class Invert(Processor):
    """The inner processor (SerialStar by default) with success and failure swapped."""

    def __init__(self, processor: Processor | None = None) -> None:
        self.processor = processor or SerialStar()

    def spec(self) -> str:
        return f"Invert({self.processor.spec()})"


class InferInvalid(Processor):
    """Fills in parameters that hold invalid values by inference from the world model,
    then runs the children in sequence."""


def all_processors(cls: type = Processor) -> dict[str, type]:
    """Every processor class defined so far (skill libraries' own included), by the name
    the skill manager knows it by: a skill process checks them against the manager's
    table when it registers."""
    out: dict[str, type] = {}
    for sub in cls.__subclasses__():
        if not sub.__name__.startswith("_"):
            out[sub.__name__] = sub
        out.update(all_processors(sub))
    return out
