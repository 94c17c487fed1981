"""`skillbus gripper-device`: an option the chosen runner would ignore is refused, naming
it (exit 2), before anything opens: before, --lockstep took no notice of --period-ms,
--object-width or --physics."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

CASES = [
    (["--lockstep", "--physics"], "--lockstep and --physics: one or the other"),
    (["--lockstep", "--period-ms", "5"], "--period-ms is for the wall clock"),
    (["--lockstep", "--object-width", "50000"], "--object-width is for the standalone device"),
    (["--physics", "--object-width", "50000"], "--object-width is for the standalone device"),
]


@pytest.mark.parametrize("args, why", CASES, ids=["lockstep-physics", "lockstep-period", "lockstep-object",
                                                  "physics-object"])
def test_an_option_the_runner_would_ignore_is_refused(args, why):
    env = {**os.environ, "SKILLBUS_BUS_URL": "nowhere://this-bus-must-not-be-opened"}
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", "gripper-device", "--channel", "/nonexistent.sock", *args],
                       capture_output=True, text=True, timeout=60, env=env)
    assert p.returncode == 2, (p.returncode, p.stdout, p.stderr)
    assert p.stderr.startswith(f"error: gripper-device: {why}"), p.stderr
    assert "Traceback" not in p.stderr
