"""One lockstep session of the physics server with a scripted participant, in a sandbox:
what the tests and benchmarks of the physics server run."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

from skillbus import paths
from skillbus.netns import Sandbox, last_json


def run_script_session(box: Sandbox, script: dict[str, Any], duration_s: float, work_dir: Path,
                       sim_args: tuple[str, ...] = (), scene: Path | None = None, timeout: float = 120.0,
                       name: str = "script") -> dict[str, Any]:
    """Runs sim_server (lockstep master, `duration_s` of sim time) and `skillbus sim-script`
    with `script`. Returns {"sim": summary, "script": summary, "record": states and replies}."""
    work_dir.mkdir(parents=True, exist_ok=True)
    script_file, out_file = work_dir / f"{name}.json", work_dir / f"{name}.out.json"
    script_file.write_text(json.dumps(script))
    sim = box.start("sim", [str(paths.binary("sim_server")), "--scene", str(scene or paths.demo_scene()),
                            "--participants", name, "--duration-s", str(duration_s), *sim_args])
    part = box.start(name, [sys.executable, "-m", "skillbus.cli", "sim-script", str(script_file), "--name", name,
                            "--out", str(out_file)])
    box.wait(sim, timeout)
    box.wait(part, 30)
    result = {"sim": last_json(sim.stdout()) or {"ok": False, "error": f"no summary: {sim.stderr()[-2000:]}"},
              "script": last_json(part.stdout()) or {"ok": False, "error": f"no summary: {part.stderr()[-2000:]}"},
              "record": json.loads(out_file.read_text()) if out_file.exists() else {}}
    return result
