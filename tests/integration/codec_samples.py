"""The canonical sample of every message type, generated from the bindings of lcmtypes/:
every field of every type gets a value (edge values of each primitive type: the extremes
of the integers, float32-exact and subnormal floats, -0.0, empty and multi-byte UTF-8
strings, the bytes 0 and 255; every variable array 1 to 3 long), by walking the
generated Python classes' ``__slots__``, ``__typenames__`` and ``__dimensions__``.

The C++ half of the codec test builds the same values field by field from a header this
script writes (``--cpp FILE``, run by tests/cpp/CMakeLists.txt at build time): the two
must agree byte for byte. A new .lcm file is covered without a change here.

    python codec_samples.py --cpp build/tests/cpp/codec_samples.hpp   # (PYTHONPATH: build/gen/python)
"""

from __future__ import annotations

import importlib
import itertools
import pkgutil
import struct
import sys
from typing import Any, Iterator

import skillbus_msgs

PACKAGE = "skillbus_msgs"

# Values of each primitive type, taken in turn (float: exact in float32; the C++ side
# gets their exact hex literals).
VALUES: dict[str, list[Any]] = {
    "int8_t": [-128, 127, -8, 0, 1],
    "int16_t": [-32768, 32767, -1600, 0, 7],
    "int32_t": [-2147483648, 2147483647, -320000, 0, 12345],
    "int64_t": [-(2 ** 63), 2 ** 63 - 1, -64000000000, 3000000000, 0],
    "float": [1.5, -2.25, 2.0 ** -149, -0.0, 2.0 ** 100, 0.09375],
    "double": [-2.25, 1.0e308, 5e-324, 0.1, -0.0, 123456789.123],
    "boolean": [True, False],
    "byte": [0, 255, 1, 254, 128],
    "string": ["héllo wörld", "", "a\"b\\c\n\t", "日本語", "SB_X"],
}
PRIMITIVES = set(VALUES)


def type_names() -> list[str]:
    """Every generated type (one per .lcm file), sorted."""
    return sorted(m.name for m in pkgutil.iter_modules(skillbus_msgs.__path__))


def type_class(name: str) -> type:
    """The class of a type by its name ("header_t") or lcm-gen's typename ("skillbus_msgs.header_t")."""
    name = name.rsplit(".", 1)[-1]
    return getattr(importlib.import_module(f"{PACKAGE}.{name}"), name)


def fields(cls: type) -> Iterator[tuple[str, str, list]]:
    """(slot, typename, dimensions) of each field in order; dimensions [] for a scalar."""
    for slot, typename, dims in zip(cls.__slots__, cls.__typenames__, cls.__dimensions__):
        yield slot, typename, list(dims or [])


class Builder:
    """Builds samples; one counter over all primitives of a sample picks the values."""

    def __init__(self) -> None:
        self.n = itertools.count()

    def primitive(self, typename: str) -> Any:
        values = VALUES[typename]
        return values[next(self.n) % len(values)]

    def message(self, cls: type) -> Any:
        m = cls()
        lengths = {d for _, _, dims in fields(cls) for d in dims if isinstance(d, str)}
        for slot, typename, dims in fields(cls):
            if slot in lengths:
                value: Any = 1 + next(self.n) % 3  # the length of an array that follows
            else:
                value = self.value(typename, [getattr(m, d) if isinstance(d, str) else d for d in dims])
            setattr(m, slot, value)
        return m

    def value(self, typename: str, dims: list[int]) -> Any:
        if dims:
            if typename == "byte" and len(dims) == 1:
                return bytes(self.primitive("byte") for _ in range(dims[0]))
            return [self.value(typename, dims[1:]) for _ in range(dims[0])]
        if typename in PRIMITIVES:
            return self.primitive(typename)
        return self.message(type_class(typename))


def samples() -> dict[str, Any]:
    """Type name -> its canonical sample."""
    return {name: Builder().message(type_class(name)) for name in type_names()}


# -- the C++ half --------------------------------------------------------------------------

CPP_INT = {"int8_t": "int8_t", "int16_t": "int16_t", "int32_t": "int32_t", "int64_t": "int64_t"}


def cpp_literal(typename: str, v: Any) -> str:
    if typename in CPP_INT:
        text = "(-INT64_C(9223372036854775807) - 1)" if v == -(2 ** 63) else f"INT64_C({v})"
        return f"static_cast<{CPP_INT[typename]}>({text})"
    if typename == "boolean":
        return "1" if v else "0"
    if typename == "byte":
        return f"static_cast<uint8_t>({v})"
    if typename == "float":
        assert struct.unpack("<f", struct.pack("<f", v))[0] == v, v  # exact in float32
        return f"static_cast<float>({float(v).hex()})"
    if typename == "double":
        return float(v).hex()
    if typename == "string":
        out = []
        for b in v.encode("utf-8"):
            c = chr(b)
            out.append("\\" + c if c in '"\\' else c if 0x20 <= b < 0x7F else f"\\{b:03o}")
        return f'std::string("{"".join(out)}")'
    raise ValueError(typename)


def cpp_assignments(value: Any, typename: str, dims: list, path: str) -> Iterator[str]:
    """C++ statements that give `path` the sample's value, field by field."""
    if dims:
        yield f"fit({path}, {len(value)});"
        for i, x in enumerate(value):
            yield from cpp_assignments(x, typename, dims[1:], f"{path}[{i}]")
    elif typename in PRIMITIVES:
        yield f"{path} = {cpp_literal(typename, value)};"
    else:
        for slot, t, d in fields(type(value)):
            yield from cpp_assignments(getattr(value, slot), t, d, f"{path}.{slot}")


def cpp_header() -> str:
    names = type_names()
    lines = ["// The canonical sample of every message type: generated by tests/integration/codec_samples.py",
             "// (--cpp) from the bindings of lcmtypes/, at build time. Do not edit.",
             "#pragma once", "#include <cstddef>", "#include <cstdint>", "#include <string>", "#include <vector>", ""]
    lines += [f'#include "{PACKAGE}/{n}.hpp"' for n in names]
    lines += ["", "namespace codec_samples {", "",
              "template <class T>", "void fit(std::vector<T>& v, std::size_t n) { v.resize(n); }",
              "template <class T, std::size_t N>", "void fit(T (&)[N], std::size_t) {}", ""]
    for name, msg in samples().items():
        lines += [f"inline {PACKAGE}::{name} make_{name}() {{", f"  {PACKAGE}::{name} m{{}};"]
        for slot, t, d in fields(type(msg)):
            lines += ["  " + s for s in cpp_assignments(getattr(msg, slot), t, d, f"m.{slot}")]
        lines += ["  return m;", "}", ""]
    lines += ["// add(name, sample) for every type", "template <class Add>", "void for_each_sample(Add&& add) {"]
    lines += [f'  add("{n}", make_{n}());' for n in names]
    lines += ["}", "", "}  // namespace codec_samples", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] != "--cpp":
        sys.exit("usage: codec_samples.py --cpp OUTPUT.hpp")
    text = cpp_header()
    try:
        with open(sys.argv[2]) as f:
            unchanged = f.read() == text
    except OSError:
        unchanged = False
    if not unchanged:  # (an unchanged header keeps codec_peer from being rebuilt)
        with open(sys.argv[2], "w") as f:
            f.write(text)
