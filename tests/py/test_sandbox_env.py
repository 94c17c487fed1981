"""The environment a Sandbox gives its processes: a PYTHONPATH the caller passes is put in
front of the one the test runs with, not in its place (else a work tree's processes import
whichever skillbus is installed)."""

import os

from skillbus.netns import Sandbox


def test_pythonpath_is_added_in_front_of_the_inherited_one(tmp_path, monkeypatch):
    box = Sandbox(log_dir=tmp_path)
    monkeypatch.setenv("PYTHONPATH", "/tree/py_skills")
    assert box.env({"PYTHONPATH": "/libs"})["PYTHONPATH"] == os.pathsep.join(["/libs", "/tree/py_skills"])
    assert box.env()["PYTHONPATH"] == "/tree/py_skills"
    monkeypatch.delenv("PYTHONPATH")
    assert box.env({"PYTHONPATH": "/libs", "X": "1"})["PYTHONPATH"] == "/libs"
    assert box.env({"X": "1"})["X"] == "1" and box.env()["SKILLBUS_BUS_URL"] == box.url
