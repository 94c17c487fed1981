"""`skillbus demo` and its run folder: a second demo never clears the folder of one that
runs (it used to pull the first one's supervisord socket away, and the first then waited
15 minutes for a session end it could no longer see); a demo whose supervisord stops
answering fails at once, naming it. A real supervisord with one trivial program."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from skillbus import demo, launch
from skillbus.system import Program


@pytest.fixture(autouse=True)
def no_multicast(monkeypatch):
    # The trivial program never opens the bus; a DDS URL keeps launch's check from asking
    # for a private network namespace (an LCM URL would join a multicast group).
    monkeypatch.setenv("SKILLBUS_BUS_URL", "dds://0")


def supervised(run_dir: Path) -> Path:
    run_dir.mkdir(parents=True, exist_ok=True)
    conf = launch.write_config(run_dir, [Program("sim", [sys.executable, "-c", "import time; time.sleep(60)"])],
                               lockstep=False)
    launch.start(conf, wait_s=30)
    return conf


def test_a_second_demo_refuses_a_run_folder_in_use(tmp_path):
    conf = supervised(tmp_path / "demo")
    try:
        with pytest.raises(demo.DemoError, match=r"is in use: the supervisord of another demo answers there"):
            demo.run(tmp_path / "demo", quiet=True)
        assert launch.status(conf) == {"sim": "RUNNING"}  # untouched: its socket and its program
        assert not demo.session_over(conf)
    finally:
        launch.shutdown(conf)


def test_a_demo_whose_supervisord_is_gone_fails_naming_it(tmp_path):
    conf = supervised(tmp_path / "demo")
    launch.shutdown(conf)
    with pytest.raises(demo.DemoError, match=r"no longer answers: its socket or process is gone"):
        demo.session_over(conf)


@pytest.mark.parametrize("seed", [-1, 2**32])
def test_a_seed_out_of_range_is_refused_before_the_last_run_is_cleared(tmp_path, seed):
    # Before, 2**32 cleared the last run's folder, then the physics server refused the
    # scene with "scatter.seed must be a whole number >= 0".
    (tmp_path / "demo").mkdir()
    (kept := tmp_path / "demo" / "demo.lcmlog").write_bytes(b"the last run")
    with pytest.raises(ValueError, match=rf"--seed {seed}: a seed is a whole number from 0 to 4294967295"):
        demo.run(tmp_path / "demo", quiet=True, seed=seed)
    assert kept.read_bytes() == b"the last run"
