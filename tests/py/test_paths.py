"""skillbus.paths: where the built programs are."""

import os

import pytest

from skillbus import paths


@pytest.mark.parametrize("name", sorted(paths._PROGRAMS))
def test_every_program_is_the_built_executable_file(name):
    path = paths.binary(name)
    assert path.is_absolute() and path.is_file() and path.name == name, path
    assert os.access(path, os.X_OK), path


def test_the_world_model_server_is_its_program_not_its_folder():
    # (it used to be build/wm_server, the folder: every caller built the path by hand)
    assert paths.binary("wm_server") == paths.build_dir().resolve() / "wm_server" / "wm_server"


def test_an_unknown_program_is_named_with_the_known_ones():
    with pytest.raises(KeyError, match=r"no program 'wm' in the build; the programs: .*wm_server"):
        paths.binary("wm")


def test_a_program_not_built_says_to_build(tmp_path, monkeypatch):
    monkeypatch.setenv("SKILLBUS_BUILD_DIR", str(tmp_path))
    with pytest.raises(FileNotFoundError, match=r"skill_mgr/skill_mgr does not exist: run `make build` first"):
        paths.binary("skill_mgr")
