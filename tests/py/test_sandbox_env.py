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


def test_a_sandbox_that_cannot_start_leaves_no_key_behind_and_the_cli_names_why(monkeypatch, tmp_path, capsys):
    # Before, its key folder and log folder stayed in /tmp, and lockstep-session ended in
    # a traceback. (No namespace is made here: unshare is made to fail.)
    import argparse
    import pytest
    from skillbus import lockstep_session, netns
    monkeypatch.setattr(netns.Sandbox, "_enter_namespace",
                        lambda self: (_ for _ in ()).throw(netns.SandboxError("unshare -rn failed: not allowed")))
    monkeypatch.setattr(netns, "_host_routes_multicast_to_lo", lambda: False)
    monkeypatch.setattr(netns.tempfile, "tempdir", str(tmp_path))
    with pytest.raises(netns.SandboxError):
        Sandbox().__enter__()
    assert list(tmp_path.iterdir()) == []
    args = argparse.Namespace(frames=10, python=1, cpp=0, timeout=10.0, json=False)
    assert lockstep_session.main(args) == 2
    assert "error: lockstep-session: no private network namespace (unshare -rn failed: not allowed)" in \
        capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
