"""The pick-and-place system run once in a sandbox, with what every test of it compares:
each process's summary and the final world model (test_pick_and_place, test_two_hosts)."""

from __future__ import annotations

import json
from pathlib import Path

from conftest import last_json, python_tool
from skillbus import cpu_layout
from skillbus.system import programs, start


def run_clear_table(box, run: Path, perception: bool = False, scene: Path | None = None, task: str | None = None,
                    physics_core: str = "off") -> dict:
    """Starts the system in `box` (any Sandbox), waits for the session to end and returns
    the summaries of the physics server, world model, manager, skill process and gripper,
    and the world model's final containment (wm_where.py). `physics_core`: placed as
    `skillbus demo --physics-core` places them (skillbus.cpu_layout)."""
    progs = programs(run, scene=scene, perception=perception, **({"task": task} if task else {}))
    procs = start(box, cpu_layout.place(progs, physics_core).programs, run)
    assert box.wait(procs["sim"], 600) == 0, procs["sim"].stderr()[-3000:]
    out = {"sim": last_json(procs["sim"].stdout())}
    for n in ("wm", "skill_mgr", "skills", "gripper", *(["map"] if perception else [])):
        assert box.wait(procs[n], 60) == 0, procs[n].stderr()[-3000:]
        out[n] = last_json(procs[n].stdout())
    where = box.start("where", python_tool("wm_where.py", str(run)))
    assert box.wait(where, 60) == 0, where.stderr()[-2000:]
    out["world_model"] = json.loads(where.stdout().strip().splitlines()[-1])
    return out
