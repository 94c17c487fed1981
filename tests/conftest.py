"""Shared pytest fixtures. Multi-process tests get a Sandbox: a private network namespace
whose processes are always stopped, also when a test fails or times out. A test that
cannot run (no namespace can be made) fails, naming why, unless SKILLBUS_ALLOW_SKIP=1
(tests/support/skip_policy.py, docs/testing.md)."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

from skillbus import paths
from skillbus import netns
from skillbus.netns import Sandbox, SandboxError
# The skip policy: a test that cannot run fails unless SKILLBUS_ALLOW_SKIP=1 (its hooks
# are registered by being here).
from support.skip_policy import cannot_run, pytest_configure, pytest_make_collect_report, pytest_runtest_makereport  # noqa: F401
from support.interrupts import restore_ctrl_c

restore_ctrl_c()  # (a run started with SIGINT ignored would pass that on to every process it starts)

TESTS = Path(__file__).resolve().parent


def _sandbox(tmp_path: Path, transport: str = "lcm"):
    try:
        box = Sandbox(log_dir=tmp_path / "logs", transport=transport)
        box.__enter__()
    except SandboxError as e:
        cannot_run(str(e))
    try:
        yield box
    finally:
        box.__exit__(None, None, None)


# The transport of the plain `sandbox` fixture: LCM, or every multi-process test on DDS
# with SKILLBUS_TEST_TRANSPORT=dds (`make test-dds`, docs/testing.md).
SANDBOX_TRANSPORT = os.environ.get("SKILLBUS_TEST_TRANSPORT", "lcm")


@pytest.fixture
def sandbox(tmp_path):
    yield from _sandbox(tmp_path, SANDBOX_TRANSPORT)


def lcm_only(why: str):
    """Marks a test that is about LCM itself (its wire, its tools): it runs on LCM only, and
    under `make test-dds` it is skipped, saying why (a skip the policy allows: there is
    nothing of it to run on DDS)."""
    def mark(test):
        test = pytest.mark.skipif(SANDBOX_TRANSPORT != "lcm", reason=f"about LCM: {why}")(test)
        return pytest.mark.allow_skip(test)
    return mark


TRANSPORTS = ("lcm", "dds")


@pytest.fixture(params=TRANSPORTS)
def transport_sandbox(request, tmp_path):
    """A sandbox on each transport in turn: LCM (udpm://) and Cyclone DDS (dds://)."""
    yield from _sandbox(tmp_path, request.param)


@pytest.fixture
def binary():
    return paths.binary


def python_tool(script: str, *args: str) -> list[str]:
    return [sys.executable, str(TESTS / "integration" / script), *args]


def last_json(text: str) -> dict:
    summary = netns.last_json(text)
    if summary is None:
        raise AssertionError(f"no JSON summary in output:\n{text[-2000:]}")
    return summary


@pytest.fixture
def device_and_driver():
    """A booted simulated gripper device (node 5, fingers that go nowhere) and a driver's
    remote node on the same in-process CAN network (tests/py: the device's heartbeat and
    status)."""
    import canopen

    from skillbus.can.device import EDS, GripperDevice
    from skillbus.can.fingers import SimFingers
    from test_untrusted_can import networks

    dev_net, peer = networks(2)
    dev = GripperDevice(dev_net, 5, EDS, fingers=SimFingers(lambda m: None))
    node = canopen.RemoteNode(5, str(EDS))
    peer.add_node(node)
    dev.boot()
    yield dev, node
    dev_net.disconnect()
    peer.disconnect()
