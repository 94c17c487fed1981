"""The skip policy of the test suite (docs/testing.md, "Skips"): a test that cannot run
fails and says why, unless SKILLBUS_ALLOW_SKIP=1 lets it be skipped.

A skip in CI hides a test that never ran (no network namespace on the runner, a program
missing): so every skip counts as a failure, its reason kept, unless

* SKILLBUS_ALLOW_SKIP=1 (or any value but 0) is set: on a developer's machine that cannot
  make a network namespace, say; then a test that cannot make its sandbox is skipped too;
* the test carries ``@pytest.mark.allow_skip`` (on a fixture's parameter:
  ``pytest.param("kernel", marks=pytest.mark.allow_skip)``): it tests something of the
  kernel the code cannot provide (the kernel's vcan0 where there is no SocketCAN), and
  its skip is the answer, not a hole.

Expected failures (xfail) are not skips. The tests' conftest.py imports the hooks.
"""

from __future__ import annotations

import os

import pytest

ALLOW_ENV = "SKILLBUS_ALLOW_SKIP"
HOW = f"a test that cannot run fails; {ALLOW_ENV}=1 lets it be skipped (docs/testing.md)"


def skips_allowed() -> bool:
    return os.environ.get(ALLOW_ENV, "") not in ("", "0")


def cannot_run(reason: str) -> None:
    """Ends a test that cannot run: a skip where skips are allowed, else a failure."""
    if skips_allowed():
        pytest.skip(reason)
    pytest.fail(f"{reason}\n({HOW})", pytrace=False)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "allow_skip: this test may be skipped without SKILLBUS_ALLOW_SKIP: what it needs is a "
                   "property of the machine the code cannot provide (the kernel's SocketCAN)")


def _reason(longrepr: object) -> str:
    if isinstance(longrepr, tuple) and len(longrepr) == 3:
        return str(longrepr[2]).removeprefix("Skipped: ")
    return str(longrepr)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    outcome = yield
    rep = outcome.get_result()
    from skillbus.netns import SandboxError
    if call.excinfo is not None and call.excinfo.errisinstance(SandboxError) and skips_allowed():
        # a test that makes its own Sandbox and cannot: as the sandbox fixture
        rep.outcome = "skipped"
        rep.longrepr = (str(item.path), item.location[1] or 0, f"Skipped: {call.excinfo.value}")
        return
    if call.excinfo is not None and call.excinfo.errisinstance(SandboxError):
        rep.sections.append(("skip policy", HOW))
    if (rep.skipped and not hasattr(rep, "wasxfail") and not skips_allowed()
            and item.get_closest_marker("allow_skip") is None):
        rep.outcome = "failed"
        rep.longrepr = f"skipped without leave: {_reason(rep.longrepr)}\n({HOW})"


@pytest.hookimpl(hookwrapper=True)
def pytest_make_collect_report(collector: pytest.Collector):
    """A whole module skipped at import (pytest.importorskip, a module-level skip)."""
    outcome = yield
    rep = outcome.get_result()
    if rep.skipped and not skips_allowed():
        rep.outcome = "failed"
        rep.longrepr = f"{collector.nodeid} skipped without leave: {_reason(rep.longrepr)}\n({HOW})"
