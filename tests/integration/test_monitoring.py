"""Monitoring a run: the demo's LCM log decodes completely with the generated types jar
(the way lcm-spy decodes), lcm-spy itself finds every type when started headless under
Xvfb, and skillbus replay plays a log back onto the bus."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import last_json, lcm_only
from skillbus import paths
from skillbus.netns import Sandbox
from skillbus.system import programs, start
from skillbus.waiting import wait_for_text

HERE = Path(__file__).resolve().parent
LCM_TYPES = len(list((paths.REPO_ROOT / "lcmtypes").glob("*.lcm")))


def mark_log(box, log: Path) -> None:
    """Returns once the logger has recorded a marker published now (monitor.mark_log,
    run inside the sandbox's network): it is recording, and has written everything
    published before."""
    code = f"from skillbus.monitor import mark_log; mark_log({str(log)!r}, timeout=20)"
    mark = box.start(f"mark-{len(box.procs)}", [sys.executable, "-c", code])
    assert box.wait(mark, 60) == 0, mark.stderr()[-2000:]


@pytest.fixture(scope="module")
def demo_log(tmp_path_factory) -> Path:
    """An LCM log of a whole ClearTable run (lcm-logger from the lcm wheel)."""
    run = tmp_path_factory.mktemp("logged")
    log = run / "run.lcmlog"
    with Sandbox(log_dir=run / "logs") as box:
        box.start("logger", [str(Path(sys.executable).parent / "lcm-logger"), "-f", str(log)])
        mark_log(box, log)  # recording before the system starts
        procs = start(box, programs(run), run)
        assert box.wait(procs["sim"], 600) == 0
        assert box.wait(procs["skill_mgr"], 60) == 0
        assert last_json(procs["skill_mgr"].stdout())["tasks"] == {"1": "Success: all succeeded"}
        mark_log(box, log)  # everything the run published is in the file
    return log


def start_xvfb(box) -> str:
    """A headless X server on a display it picks itself (-displayfd: free, also with other
    runs on the machine); returns the display once the server has announced it, which
    it does once it listens."""
    xvfb = box.start("xvfb", ["Xvfb", "-displayfd", "1", "-screen", "0", "1200x800x24"])
    number = xvfb.wait_for(re.compile(r"^(\d+)$", re.M), 30, stream="stdout", what="Xvfb announcing its display")
    return f":{number.group(1)}"


def java_lcm_jar() -> str:
    jar = Path(sys.executable).parent.parent / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / \
        "site-packages" / "share" / "java" / "lcm.jar"
    assert jar.exists(), jar
    return str(jar)


def test_every_message_of_a_run_decodes_with_the_types_jar(demo_log, tmp_path):
    classes = tmp_path / "classes"
    classes.mkdir()
    cp = f"{java_lcm_jar()}:{paths.types_jar()}"
    subprocess.run(["javac", "-nowarn", "-cp", cp, "-d", str(classes), str(HERE / "JarDecodeCheck.java")], check=True)
    out = subprocess.run(["java", "-cp", f"{cp}:{classes}", "JarDecodeCheck", str(paths.types_jar()), str(demo_log)],
                         capture_output=True, text=True, check=True).stdout
    r = json.loads(out)
    assert r["types"] == LCM_TYPES  # every .lcm file became a class in the jar
    channels = r["channels"]
    for ch in ("SB_SIM_STATE", "SB_ROBOT_ARM_STATE", "SB_ROBOT_OBJECTS", "SB_ROBOT_ARM_CMD", "SB_ROBOT_CMD_REPLY",
               "SB_SIM_GRIPPER_CMD", "SB_SKILL_PROGRESS", "SB_WM_TXN", "SB_WM_CHANGES", "SB_CAN_SYNC",
               "SB_LOCKSTEP_CLOCK", "SB_MOTION_REQ", "SB_MOTION_REP"):
        assert channels.get(ch, [0, 0])[0] > 0, (ch, channels)
    assert all(bad == 0 for _, bad in channels.values()), channels


@pytest.mark.skipif(not shutil.which("Xvfb") or not shutil.which("import"),
                    reason="Xvfb and ImageMagick's import are needed to run lcm-spy headless")
@lcm_only("lcm-spy and lcm-logplayer speak LCM only")
def test_lcm_spy_finds_every_type_and_shows_the_replayed_channels(demo_log, sandbox, tmp_path):
    display = start_xvfb(sandbox)
    spy = sandbox.start("spy", [sys.executable, "-m", "skillbus.cli", "spy"], env={"DISPLAY": display})
    found = wait_for_text(lambda: spy.stdout() + spy.stderr(), re.compile(r"Found (\d+) LCM types"), 60,
                          "lcm-spy finding the types", ended=lambda: spy.returncode, interval=0.2,
                          diagnostic=lambda: spy.stdout()[-2000:] + spy.stderr()[-2000:])
    assert int(found.group(1)) >= LCM_TYPES, spy.stdout()[-2000:] + spy.stderr()[-2000:]
    replay = sandbox.start("replay", [sys.executable, "-m", "skillbus.cli", "replay", str(demo_log), "--speed", "20"])
    assert sandbox.wait(replay, 120) == 0, replay.stderr()
    shot = tmp_path / "spy.png"
    grab = sandbox.start("import", ["import", "-display", display, "-window", "root", str(shot)])
    assert sandbox.wait(grab, 30) == 0 and shot.stat().st_size > 3_000  # a blank 1200x800 screen is ~1 kB
    assert "Exception" not in spy.stderr().replace("ClassDiscoverer", "")


def test_replay_names_a_missing_log(sandbox, tmp_path):
    p = sandbox.start("replay", [sys.executable, "-m", "skillbus.cli", "replay", str(tmp_path / "none.lcmlog")])
    assert sandbox.wait(p, 30) == 2
    assert "no such log file" in p.stderr()
