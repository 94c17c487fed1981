"""One episode, start to end, in a network namespace of its own (skillbus.netns.Sandbox):
its randomized scene and world-model scene written into its folder, the whole system
started under lockstep (physics, world model, skill manager, motion service, CANopen
gripper, the skill process with the manipulation library) with the task (ManipTask of
the config's skills) started at the manager's first tick, and a recorder of every
message (skillbus.udpm_record). The session ends a few frames after the task (or
at ``max_sim_s``); the rows come from the log (skillbus.generate.record).

Run alone (``skillbus generate CONFIG --episode K --seed S``) an episode gives the same
digests as in a batch: its scene, its task and the lockstep depend on its seed alone.
"""

from __future__ import annotations

import json
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import yaml

from skillbus.generate.config import GenerateConfig, episode_seed
from skillbus.generate.randomize import randomized

WALL_SLACK_S = 120.0  # start-up and tear-down beyond the sim time at a real-time factor of 1


class EpisodeError(RuntimeError):
    """The episode could not be run or recorded (a process died, frames were lost): it
    is not a demonstration, neither a success nor a failure; the runner retries it."""


def _mark(box: Any, log: Path, name: str) -> None:
    p = box.start(name, [sys.executable, "-c", "import sys; from skillbus.monitor import mark_log; "
                                               "mark_log(sys.argv[1], timeout=20)", str(log)])
    if box.wait(p, 30) != 0:
        raise EpisodeError(f"the recorder did not record ({name}): {p.stderr()[-500:]}")


def compact_task(skills: list[dict]) -> str:
    """The task as one line of YAML (flow style) in double quotes, a word of the manager's
    ``--start`` (space-separated KEY=VALUE words; double quotes keep spaces). A path to
    a file in the episode's folder instead would make the episode's messages, so its
    session digest, depend on where it ran.

    >>> compact_task([{"name": "open", "Object": "my drawer", "distance": 0.15}])
    '"{skills: [{name: open, Object: my drawer, distance: 0.15}]}"'
    """
    text = yaml.safe_dump({"skills": skills}, default_flow_style=True, sort_keys=False, width=1 << 30).strip()
    if '"' in text or "\n" in text:
        raise EpisodeError(f"the task cannot be handed to the skill manager as one line: {text[:200]}")
    return f'"{text}"'


def run_episode(cfg: GenerateConfig, seed: int, request: int, work: Path, attempt: int = 0) -> dict[str, Any]:
    """Runs episode `request` of the run with seed `seed`; its result (rows, labels,
    digests). Raises EpisodeError when it could not be run whole."""
    from skillbus.generate import record
    from skillbus.netns import Sandbox, last_json
    from skillbus.sim import scene as scenes
    from skillbus.system import programs, start
    eseed = episode_seed(seed, request)
    folder = Path(work) / f"episode-{request:06d}" / f"attempt-{attempt}"
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    base = scenes.load(cfg.scene)
    base["cameras"] = list(base.get("cameras", [])) + list(cfg.cameras)
    doc, chosen = randomized(base, cfg.randomize, eseed)
    scene = scenes.save(doc, folder / "episode.scene.json", cfg.scene)
    (folder / "episode.ttl").write_text(scenes.to_turtle(scenes.load(scene)))
    ids = scenes.element_ids(scene)
    for label in (cfg.arm, cfg.gripper):
        if label not in ids:
            raise EpisodeError(f"the scene has no element labelled {label!r} (arm/gripper in the config)")
    (folder / "task.yaml").write_text(yaml.safe_dump({"skills": cfg.skills}, sort_keys=False))  # (to read)
    task = f"ManipTask Task={compact_task(cfg.skills)} Arm={ids[cfg.arm]} Gripper={ids[cfg.gripper]}"
    frames = int(round(cfg.max_sim_s * 1000 / cfg.frame_ms))
    progs = programs(folder, scene=scene, task=task, manip=True, frame_ms=cfg.frame_ms,
                     extra_sim=("--frames", str(frames)))
    log = folder / "episode.lcmlog"
    t0 = time.monotonic()
    with Sandbox(log_dir=folder / "logs") as box:
        # skillbus's recorder, not lcm-logger: lcm-logger's 30-message queue overflowed now
        # and then while two episodes kept both cores busy (skillbus.udpm_record).
        box.start("logger", [sys.executable, "-m", "skillbus.cli", "record", str(log)])
        _mark(box, log, "mark-start")  # the logger records before the first frame
        procs = start(box, progs, folder)
        rc = box.wait(procs["sim"], cfg.max_sim_s + WALL_SLACK_S)
        for name in ("skill_mgr", "skills", "wm", "gripper"):
            try:
                box.wait(procs[name], 30)
            except Exception:
                pass
        _mark(box, log, "mark-end")  # everything of the session is in the log
        sim = last_json(procs["sim"].stdout()) or {}
        mgr = last_json(procs["skill_mgr"].stdout()) or {}
        if rc != 0 or not sim.get("session_digest"):
            raise EpisodeError(f"the physics server ended with {rc}: {procs['sim'].stderr()[-800:]}")
        dead = [n for n in ("skill_mgr", "skills", "wm", "gripper") if (procs[n].returncode or 0) < 0]
        if dead:
            raise EpisodeError(f"killed during the episode: {', '.join(dead)}")
    wall = time.monotonic() - t0
    result = str((mgr.get("tasks") or {}).get("1", f"the task did not end within {cfg.max_sim_s:.0f} s of sim time"))
    stride = max(1, int(round(1000.0 / (cfg.fps * cfg.frame_ms))))
    try:
        ep = record.read(log, stride, cfg.frame_ms)
    except record.RecordError as e:
        raise EpisodeError(str(e)) from None
    success = result.startswith("Success")
    failed = [s for s in ep.segments if s["state"] == "Failure"]
    reason = "" if success else (f"{failed[0]['skill']}: {failed[0]['message']}" if failed else result)
    return {"request": request, "seed": eseed, "attempt": attempt, "success": success, "failure_reason": reason,
            "task_result": result, "state_digest": sim.get("state_digest"), "session_digest": sim.get("session_digest"),
            "sim_s": ep.frames * cfg.frame_ms / 1000.0, "wall_s": wall, "randomized": chosen,
            "segments": ep.segments, "episode": ep, "folder": str(folder)}


def summary_line(r: dict[str, Any]) -> str:
    label = "success" if r["success"] else f"failure ({r['failure_reason']})"
    return json.dumps({"request": r["request"], "seed": r["seed"], "result": label, "session_digest": r["session_digest"]})
