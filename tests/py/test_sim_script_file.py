"""`skillbus sim-script`'s script is checked whole before the session: before, a top-level
list or a record_every of "x" ended in a traceback, and a gripper step without a width
failed its frame during the run, and with it the whole lockstep session; an --out that
cannot be written was found out after the session, its summary lost."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from skillbus.sim.script import ScriptError, load_script

BAD = [
    ([{"at_s": 0.1, "gripper": {"width": 0.0}}], "a script is an object with steps, not a list"),
    ({"record_every": "x", "steps": []}, "record_every must be a whole number of frames, 1 or more, not 'x'"),
    ({"record_every": 0, "steps": []}, "record_every must be a whole number of frames, 1 or more, not 0"),
    ({"steps": [{"at_s": 0.1, "gripper": {"id": "g"}}]}, "steps[0]: gripper needs a number width"),
    ({"steps": [{"at_s": 0.1, "arm": {"joints": ["j1"]}}]}, "steps[0]: arm needs joints and points"),
    ({"steps": [{"at_s": 0.1, "arm": {"joints": ["j1"], "points": [[1.0]]}}]},
     "steps[0]: arm.points[0] is not [t, q] or [t, q, qd]"),
    ({"steps": [{"at_s": 0.1, "raw": {"hex": "zz"}}]}, "steps[0]: raw needs hex bytes"),
]


@pytest.mark.parametrize("doc, why", BAD, ids=["list", "every-text", "every-0", "no-width", "no-points", "short-point",
                                                "bad-hex"])
def test_a_script_that_cannot_be_played_is_refused_naming_why(tmp_path, doc, why):
    f = tmp_path / "s.json"
    f.write_text(json.dumps(doc))
    with pytest.raises(ScriptError) as e:
        load_script(str(f))
    assert why in str(e.value), str(e.value)


def test_a_wrong_value_on_purpose_is_still_played():
    # (a NaN speed is the physics server's to refuse: tests send one)
    import tempfile
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        f.write('{"steps": [{"at_s": 0.1, "gripper": {"width": 0.02, "speed": NaN}}]}')
    try:
        assert len(load_script(f.name)["steps"]) == 1
    finally:
        os.unlink(f.name)


def test_an_out_file_that_cannot_be_written_is_refused_before_the_session(tmp_path):
    f = tmp_path / "s.json"
    f.write_text(json.dumps({"steps": []}))
    env = {**os.environ, "SKILLBUS_BUS_URL": "nowhere://this-bus-must-not-be-opened", "SKILLBUS_NETNS": "1"}
    p = subprocess.run([sys.executable, "-m", "skillbus.cli", "sim-script", str(f), "--out", str(tmp_path / "no" / "x.json")],
                       capture_output=True, text=True, timeout=60, env=env)
    assert p.returncode == 2 and "error: --out" in p.stderr and "No such file or directory" in p.stderr, p.stderr
