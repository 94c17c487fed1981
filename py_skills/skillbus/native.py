"""skillbus_native, the C++ hot paths for Python (common/python), when it can be used.

The module is built by CMake into the build tree (``make build``). Without it, or with
``SKILLBUS_NATIVE=0`` (to compare, or to rule it out), everything runs in Python: the
same bytes, digests and refusals (the tests run both ways), at Python's speed.
"""

from __future__ import annotations

import logging
import os
from typing import Any

log = logging.getLogger("skillbus")

ENV = "SKILLBUS_NATIVE"
_module: Any = None
_looked = False


def module() -> Any:
    """skillbus_native, or None (not built, or switched off with SKILLBUS_NATIVE=0)."""
    global _module, _looked
    if os.environ.get(ENV, "1") == "0":
        return None
    if not _looked:
        _looked = True
        try:
            import skillbus_native
            _module = skillbus_native
        except ImportError as e:
            log.info("skillbus_native is not built (%s; make build): Python does its work", e)
    return _module
