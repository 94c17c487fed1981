"""kill -9 of the skill manager under supervisord: every skill is listed again within
5 s of its restart and the next ClearTable succeeds (the skill processes keep running and
register again; the new manager loads its world copy before the task)."""

import json

from conftest import python_tool


def test_a_killed_manager_gets_its_skills_back_and_clears_the_table(sandbox, tmp_path):
    run = tmp_path / "sup"
    run.mkdir()
    scenario = sandbox.start("scenario", python_tool("manager_restart_scenario.py", str(run)))
    assert sandbox.wait(scenario, 420) == 0, scenario.stdout()[-3000:] + scenario.stderr()[-3000:]
    r = json.loads(scenario.stdout().strip().splitlines()[-1])
    print({k: v for k, v in r.items() if k != "clear_output"})
    assert r["registered"] and r["restarted"], r
    assert r["listed_again"] and r["listed_after_restart_s"] < 5.0, r
    assert r["clear_exit"] == 0, r["clear_output"]
