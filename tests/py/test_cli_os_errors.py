"""A command that cannot use a file or folder it was given fails in one line naming it
(exit 1), never with a traceback. Seen: `skillbus demo --run-dir /proc/nope` and
`skillbus launch --run-dir /etc/passwd` ended in a FileNotFoundError / NotADirectoryError
traceback. No bus is opened: each fails before anything starts."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest


@pytest.mark.parametrize("command", [["demo"], ["launch", "--wall-clock"], ["launch"]])
def test_a_run_folder_that_cannot_be_made_is_named(tmp_path, command):
    afile = tmp_path / "afile"
    afile.write_text("not a folder")
    env = {**os.environ, "SKILLBUS_NETNS": "1", "SKILLBUS_BUS_URL": "dds://0"}  # (nothing reaches a network)
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", *command, "--run-dir", str(afile / "run")],
                       capture_output=True, text=True, timeout=120, env=env)
    assert p.returncode == 1, (p.returncode, p.stdout, p.stderr)
    assert "Traceback" not in p.stderr, p.stderr
    assert f"error: skillbus {command[0]}: Not a directory: '{afile}/run" in p.stderr, p.stderr
