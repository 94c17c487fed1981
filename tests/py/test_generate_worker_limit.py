"""A generation worker that never ends (stuck past its episode's own limits) is killed
after generate's limit for it (skillbus.generate.runner.worker_time_limit) and its episode
counted as broken, to be run again, instead of holding the dataset for ever. The worker is
a stand-in process here; the real ones are tests/integration/test_generate*.py's."""

from __future__ import annotations

import os
import time
from types import SimpleNamespace

from skillbus.generate import runner


def test_a_worker_past_its_limit_is_killed_and_its_episode_broken(tmp_path, monkeypatch):
    pid_file = tmp_path / "pid"
    monkeypatch.setattr(runner, "worker_argv",
                        lambda *a: ["sh", "-c", f"echo $$ > {pid_file}; exec sleep 60"])
    monkeypatch.setattr(runner, "worker_time_limit", lambda cfg: 1.0)
    t0 = time.monotonic()
    r = runner.run_local(SimpleNamespace(max_sim_s=1.0), seed=1, request=3, attempt=0, work=tmp_path)
    assert time.monotonic() - t0 < 10
    assert r == {"error": "the worker gave no result within 1 s (killed)"}
    pid = int(pid_file.read_text())
    try:
        os.kill(pid, 0)
        alive = True
    except ProcessLookupError:
        alive = False
    assert not alive, "the worker is still running"
    assert not runner._live  # (no longer among the workers to stop)


def test_the_limit_is_the_episodes_own_bound_and_some():
    cfg = SimpleNamespace(max_sim_s=240.0)
    assert runner.worker_time_limit(cfg) == 240.0 + runner.WALL_SLACK_S + runner.WORKER_SLACK_S
