"""The skip policy (tests/support/skip_policy.py): without SKILLBUS_ALLOW_SKIP a test that
cannot run fails and names why; with it, it is skipped; @pytest.mark.allow_skip (the
kernel's SocketCAN) is skipped either way. Runs pytest on a small suite in a subprocess."""

import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parents[1]

CONFTEST = f"""
import sys
sys.path.insert(0, {str(TESTS)!r})
from support.skip_policy import pytest_configure, pytest_make_collect_report, pytest_runtest_makereport  # noqa
"""

SUITE = """
import pytest
from skillbus.netns import SandboxError
from support.skip_policy import cannot_run


@pytest.fixture
def box():
    cannot_run("no private network namespace (unshare -rn failed: EPERM)")


def test_plain_skip():
    pytest.skip("no frobnicator here")


@pytest.mark.skipif(True, reason="Xvfb is missing")
def test_skipif():
    pass


def test_fixture_cannot_run(box):
    pass


def test_own_sandbox_fails():
    raise SandboxError("no namespace and no multicast route to lo")


@pytest.mark.allow_skip
def test_allowed():
    pytest.skip("this kernel has no SocketCAN")


@pytest.fixture(params=["virtual", pytest.param("kernel", marks=pytest.mark.allow_skip)])
def variant(request):
    if request.param == "kernel":
        pytest.skip("cannot create vcan0")
    return request.param


def test_variants(variant):
    pass


@pytest.mark.xfail(reason="known", strict=True)
def test_xfail():
    assert False


def test_passes():
    pass
"""


def run_suite(tmp_path, allow: str | None) -> dict[str, tuple[str, str]]:
    """Runs the suite; test name -> (outcome, message) from its JUnit XML."""
    (tmp_path / "conftest.py").write_text(CONFTEST)
    (tmp_path / "test_suite.py").write_text(SUITE)
    env = {k: v for k, v in os.environ.items() if k != "SKILLBUS_ALLOW_SKIP"}
    if allow is not None:
        env["SKILLBUS_ALLOW_SKIP"] = allow
    xml = tmp_path / "out.xml"
    subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--junitxml={xml}",
                    f"--rootdir={tmp_path}", "-c", os.devnull, str(tmp_path / "test_suite.py")],
                   cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    out = {}
    for case in ET.parse(xml).getroot().iter("testcase"):
        kids = [k for k in case if k.tag in ("failure", "error", "skipped")]
        kind = kids[0].tag if kids else "passed"
        text = (kids[0].get("message") or "") + (kids[0].text or "") if kids else ""
        if kind == "skipped" and kids[0].get("type") == "pytest.xfail":
            kind = "xfailed"
        out[case.get("name")] = ("failed" if kind in ("failure", "error") else kind, text)
    return out


def test_without_leave_a_test_that_cannot_run_fails_naming_why(tmp_path):
    r = run_suite(tmp_path, None)
    for name, why in [("test_plain_skip", "no frobnicator here"), ("test_skipif", "Xvfb is missing"),
                      ("test_fixture_cannot_run", "unshare -rn failed: EPERM"),
                      ("test_own_sandbox_fails", "no namespace and no multicast route to lo")]:
        outcome, text = r[name]
        assert outcome == "failed" and why in text, (name, r[name])
    assert "SKILLBUS_ALLOW_SKIP=1" in r["test_plain_skip"][1]
    # the kernel's SocketCAN: allowed to be skipped
    assert r["test_allowed"][0] == "skipped" and r["test_variants[kernel]"][0] == "skipped"
    assert r["test_variants[virtual]"][0] == "passed" and r["test_passes"][0] == "passed"
    assert r["test_xfail"][0] == "xfailed"  # an expected failure is no skip


@pytest.mark.parametrize("allow", ["1", "yes"])
def test_with_leave_they_are_skipped(tmp_path, allow):
    r = run_suite(tmp_path, allow)
    for name in ("test_plain_skip", "test_skipif", "test_fixture_cannot_run", "test_own_sandbox_fails",
                 "test_allowed", "test_variants[kernel]"):
        assert r[name][0] == "skipped", (name, r[name])
    assert "no namespace and no multicast route to lo" in r["test_own_sandbox_fails"][1]
    assert r["test_passes"][0] == "passed" and r["test_xfail"][0] == "xfailed"


def test_zero_is_no_leave(tmp_path):
    assert run_suite(tmp_path, "0")["test_plain_skip"][0] == "failed"
