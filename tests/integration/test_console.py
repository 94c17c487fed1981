"""The console (`skillbus console`) in a real browser: Debian's Chromium, headless, driven
by Playwright (console_browser.py, run inside the test's network namespace), against the
pick-and-place system in lockstep with no task of its own.

* ClearTable started from the skill form: its tree goes Running to Success, and the tree
  the page ends with is the manager's final tree, node for node, also when the console
  loses every third progress message (it catches up from SKILL.tasks).
* A task started from the CLI: paused (no tick while paused), stepped (one tick),
  resumed and stopped from the page; the CLI's run ends saying it failed, stopped (on
  the wall clock: the task runs on between the page's clicks, and must not end there).
* An element renamed on the world page: `skillbus wm get` shows the new label; an edit
  of an element another page changed since it was read is refused, naming the change.

Screenshots of each page go to $SKILLBUS_TEST_ARTIFACTS (default build/test-artifacts)
/console; docs/console.md shows them."""

from __future__ import annotations

import json
import os
import re
import signal
import sys
from pathlib import Path

import pytest

from conftest import last_json
from skillbus import paths
from skillbus.system import programs, start
from support.held_task import hold_task

DRIVER = Path(__file__).parent / "console_browser.py"
CHROMIUM = Path("/usr/bin/chromium")
SHOTS = Path(os.environ.get("SKILLBUS_TEST_ARTIFACTS", paths.REPO_ROOT / "build" / "test-artifacts")) / "console"


@pytest.fixture
def system(sandbox, tmp_path):
    """The pick-and-place system under lockstep, without a task: tasks come from the page
    or the CLI. skillbus record records it from the start (for the replay)."""
    if not CHROMIUM.exists():
        pytest.fail(f"{CHROMIUM} is missing: `make test` installs Debian's chromium (deploy/setup.sh)")
    (tmp_path / "run").mkdir()
    log = tmp_path / "run" / "run.lcmlog"
    procs = {"logger": sandbox.start("logger", [sys.executable, "-m", "skillbus.cli", "record", str(log)])}
    procs.update(start(sandbox, programs(tmp_path / "run", task=None), tmp_path / "run"))
    procs["skills"].wait_for("registered", 60)
    return procs


@pytest.fixture
def wall_clock_system(sandbox, tmp_path):
    """The same system on the wall clock (a ClearTable of about half a minute): a test that
    lets the task run between a browser's clicks finds it still running."""
    if not CHROMIUM.exists():
        pytest.fail(f"{CHROMIUM} is missing: `make test` installs Debian's chromium (deploy/setup.sh)")
    (tmp_path / "run").mkdir()
    procs = start(sandbox, programs(tmp_path / "run", task=None, lockstep=False), tmp_path / "run")
    procs["skills"].wait_for("registered", 60)
    return procs


def console(sandbox, *extra: str) -> str:
    """Starts `skillbus console --port 0` in the sandbox; its URL."""
    p = sandbox.start(f"console-{len(sandbox.procs)}", [sys.executable, "-m", "skillbus.cli", "console", "--port", "0",
                                                        *extra])
    m = p.wait_for(re.compile(r"skillbus console: (http://\S+)"), 30, stream="stdout")
    return m.group(1)


def start_browser(sandbox, url: str, scenario: str, *extra: str):
    return sandbox.start(f"browser-{scenario}", [sys.executable, str(DRIVER), url, scenario, "--shots", str(SHOTS),
                                                 *extra])


def browser_result(sandbox, p, scenario: str, timeout: float = 600) -> dict:
    rc = sandbox.wait(p, timeout)
    assert rc == 0, f"the browser scenario {scenario} failed (screenshot in {SHOTS}):\n{p.stderr()[-4000:]}"
    return last_json(p.stdout())


def browser(sandbox, url: str, scenario: str, *extra: str, timeout: float = 600) -> dict:
    """Runs one scenario of console_browser.py; what it saw."""
    return browser_result(sandbox, start_browser(sandbox, url, scenario, *extra), scenario, timeout)


def cli(sandbox, *args: str, timeout: float = 60) -> tuple[int, str, str]:
    p = sandbox.start(f"cli-{args[0]}-{len(sandbox.procs)}", [sys.executable, "-m", "skillbus.cli", *args])
    rc = sandbox.wait(p, timeout)
    return rc, p.stdout(), p.stderr()


def manager_final_tree(sandbox, task: int) -> list[dict]:
    """The manager's own final tree of a finished task (`skillbus watch --json`, which
    reads it from SKILL.tasks)."""
    rc, out, err = cli(sandbox, "watch", str(task), "--json", "--timeout", "10")
    result = last_json(out)
    assert result and result["ended"], out + err
    return result["tree"]


def same_tree(rows: list[dict], tree: list[dict]) -> None:
    assert [(r["id"], r["state"], r["message"]) for r in rows] == \
        [(n["id"], n["state"], n["message"]) for n in tree]


def test_clear_table_started_from_the_form_runs_to_success_and_its_recording_replays(sandbox, system, tmp_path):
    url = console(sandbox)
    seen = browser(sandbox, url, "start_clear_table")
    assert seen["states"][0] == "Running" and seen["states"][-1] == "Success", seen["states"]
    assert f"task {seen['task']} started: ClearTable" in seen["message"]
    final = manager_final_tree(sandbox, seen["task"])
    assert len(final) > 10  # a whole ClearTable: locate, pick and place of every cube
    same_tree(seen["rows"], final)  # no state of any node lost on the way
    assert seen["canvas"] == 1 and re.match(r"frame \d+ ", seen["live3d"]), seen  # the live 3D view draws

    # The run, recorded by skillbus record, on the Replay page: scrubbed to a frame where a
    # cube is in the gripper, in the world model and in the physics (finger contacts).
    system["logger"].popen.send_signal(signal.SIGINT)  # (it closes its log)
    assert sandbox.wait(system["logger"], 10) is not None
    seen = browser(sandbox, url, "replay_log", "--log", str(tmp_path / "run" / "run.lcmlog"))
    assert seen["first"] < seen["frame"] < seen["last"], seen
    assert "finger_left" in seen["contacts"] and "finger_right" in seen["contacts"], seen
    assert re.search(r"session digest [0-9a-f]{64}", seen["digest"]), seen
    assert "Grasp" in seen["tasks"] and "Running" in seen["tasks"], seen


def test_with_every_third_progress_lost_the_page_still_ends_with_the_managers_tree(sandbox, system):
    """The console hears only two progress messages in three (a full queue, a lossy
    network): it reads what it missed from the manager (SKILL.tasks)."""
    url = console(sandbox, "--lose-progress-every", "3")
    seen = browser(sandbox, url, "start_clear_table")
    assert seen["states"][-1] == "Success", seen["states"]
    same_tree(seen["rows"], manager_final_tree(sandbox, seen["task"]))


def test_a_task_started_from_the_cli_is_paused_stepped_resumed_and_stopped_from_the_page(sandbox,
                                                                                         wall_clock_system):
    url = console(sandbox)
    page = start_browser(sandbox, url, "control_cli_task", "--task", "1")
    page.wait_for("READY", 60, stream="stdout")
    holder = hold_task(sandbox, 1)
    run = sandbox.start("run", [sys.executable, "-m", "skillbus.cli", "run", "ClearTable", "--timeout", "300"])
    # Held as soon as it exists: a browser beside other work can be slower than the task
    # (it once found it done); on the wall clock it also runs on while the page resumes it.
    holder.wait_for("held", 150, stream="stdout", what="task 1 held (paused)")
    seen = browser_result(sandbox, page, "control_cli_task")
    assert seen["after_first_resume"] > seen["held"] + 3, seen  # the page's resume ticks it on
    assert seen["after_pause"] == seen["paused_at"], seen  # no tick while paused
    assert seen["after_step"] == seen["after_pause"] + 1, seen  # one step: one tick
    assert seen["after_resume"] > seen["after_step"] + 3, seen
    assert seen["final"] == "Failure", seen
    assert sandbox.wait(run, 30) == 1, run.stdout() + run.stderr()
    assert "task 1: Failure" in run.stdout(), run.stdout()


def test_an_edit_on_the_world_page_is_in_the_world_model_and_a_stale_one_is_refused(sandbox, system):
    from skillbus.sim.scene import element_ids
    cube = element_ids(paths.demo_scene())["cube_red"] if "cube_red" in element_ids(paths.demo_scene()) else \
        sorted(v for k, v in element_ids(paths.demo_scene()).items() if v.startswith("skiros:Cube"))[0]
    url = console(sandbox)
    seen = browser(sandbox, url, "edit_element", "--element", cube)
    assert "done" in seen["renamed"], seen
    assert f"{cube} changed since it was read (label 'renamed in the console' -> 'renamed by someone else')" \
        in seen["stale"], seen
    rc, out, err = cli(sandbox, "wm", "get", cube, "--json")
    assert rc == 0, out + err
    assert json.loads(out)["label"] == "renamed by someone else"  # the refused edit changed nothing


def test_tree_expands_clear_table_before_it_runs(sandbox, system):
    """`skillbus tree`: nested compounds expanded by their skill process, down to the
    primitives, with the world as it is (three cubes: three transfers)."""
    rc, out, err = cli(sandbox, "tree", "ClearTable")
    assert rc == 0, out + err
    lines = out.splitlines()
    assert lines[0].startswith("ClearTable ["), out
    assert sum(1 for line in lines if line.strip().startswith("Grasp")) == 3, out
    assert "cannot expand" not in out, out


def test_screenshots_are_in_the_docs():
    """The docs show the pages the tests above photographed (copied from the artefacts
    when they change: cp build/test-artifacts/console/console-*.png docs/images/)."""
    text = (paths.REPO_ROOT / "docs" / "console.md").read_text()
    for name in ("console-skills.png", "console-task-running.png", "console-task-paused.png", "console-world.png",
                 "console-world-stale.png", "console-replay.png", "console-3d.png"):
        assert f"images/{name}" in text and (paths.REPO_ROOT / "docs" / "images" / name).exists(), name
