"""A generation config (YAML)::

    scene: ../scenes/cabinet.scene.json      # the base scene (relative to this file)
    task: drawer_pick_place.yaml             # a task file (skills: ...), or `skills:` inline
    instruction: Put the red cube in the drawer and close it.
    fps: 10                                  # recorded rows per second of sim time
    max_sim_s: 240                           # an episode that has not ended by then fails
    retries: 1                               # a broken episode (a process killed, frames lost) is run again
    cameras:                                 # depth cameras added to the scene, recorded at their rate
      - {name: overhead, pose: [0.25, -0.2, 1.3, 1, 0, 0, 0], width: 80, height: 60, rate_hz: 5}
    randomize:                               # skillbus.generate.randomize
      objects:
        red: {x: [0.40, 0.50], y: [0.05, 0.20], yaw: [-0.6, 0.6], size: [0.045, 0.055],
              colors: [red, orange, yellow]}
      articulated:
        cabinet: {x: [-0.02, 0.02], y: [-0.02, 0.02], yaw: [-0.05, 0.05]}

Every path is relative to the config file. ConfigError names the key that is wrong.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml


class ConfigError(ValueError):
    pass


@dataclass
class GenerateConfig:
    path: Path
    scene: Path
    skills: list[dict]
    instruction: str
    fps: float = 10.0
    max_sim_s: float = 240.0
    retries: int = 1
    frame_ms: float = 20.0
    randomize: dict = field(default_factory=dict)
    cameras: list = field(default_factory=list)  # depth cameras added to the scene (recorded)
    arm: str = "arm"          # labels of the robot's Arm and Gripper elements
    gripper: str = "gripper"


def _number(data: dict, key: str, default: float, lo: float, where: str) -> float:
    v = data.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not v >= lo:
        raise ConfigError(f"{where}: {key} must be a number >= {lo}, not {v!r}")
    return float(v)


def load(path: str | Path) -> GenerateConfig:
    path = Path(path).resolve()
    if not path.is_file():
        raise ConfigError(f"{path}: no such file")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as e:
        raise ConfigError(f"{path}: not valid YAML: {e}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: must be a mapping (key: value)")
    where = str(path)
    if not isinstance(data.get("scene"), str):
        raise ConfigError(f"{where}: scene (a scene file) is missing")
    scene = (path.parent / data["scene"]).resolve()
    if not scene.is_file():
        raise ConfigError(f"{where}: scene names a file that does not exist: {scene}")
    if "skills" in data:
        skills = data["skills"]
    elif isinstance(data.get("task"), str):
        task = (path.parent / data["task"]).resolve()
        if not task.is_file():
            raise ConfigError(f"{where}: task names a file that does not exist: {task}")
        skills = (yaml.safe_load(task.read_text()) or {}).get("skills")
    else:
        raise ConfigError(f"{where}: task (a task file) or skills (a list) is missing")
    if not isinstance(skills, list) or not skills or not all(isinstance(s, dict) and "name" in s for s in skills):
        raise ConfigError(f"{where}: the task's skills must be a non-empty list of mappings with a name")
    randomize = data.get("randomize") or {}
    if not isinstance(randomize, dict):
        raise ConfigError(f"{where}: randomize must be a mapping")
    cameras = data.get("cameras") or []
    if not isinstance(cameras, list) or not all(isinstance(c, dict) and c.get("name") for c in cameras):
        raise ConfigError(f"{where}: cameras must be a list of scene cameras, each with a name (docs/scene.md)")
    retries = data.get("retries", 1)
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise ConfigError(f"{where}: retries must be a whole number >= 0, not {retries!r}")
    fps, frame_ms = _number(data, "fps", 10.0, 0.1, where), _number(data, "frame_ms", 20.0, 1, where)
    _check_timing(fps, frame_ms, scene, where)
    return GenerateConfig(path=path, scene=scene, skills=skills,
                          instruction=str(data.get("instruction") or f"task of {path.stem}"),
                          fps=fps, max_sim_s=_number(data, "max_sim_s", 240.0, 1, where),
                          retries=retries, cameras=cameras, frame_ms=frame_ms, randomize=randomize,
                          arm=str(data.get("arm", "arm")), gripper=str(data.get("gripper", "gripper")))


TICK_MS = 40.0  # the skill manager's tick period (25 Hz): its ticks fall on frames


def _whole(x: float) -> bool:
    return abs(x - round(x)) < 1e-9 and round(x) >= 1


def _check_timing(fps: float, frame_ms: float, scene: Path, where: str) -> None:
    """Refused here, before any episode runs: a frame that is not a whole number of physics
    steps (the physics server refuses it, and every episode would break), one that does
    not divide the manager's tick (skills would tick at a fraction of their rate), and a
    row rate that is not a whole number of frames (the dataset would say fps while its
    rows come at another rate)."""
    try:
        step_ms = float((json.loads(scene.read_text()).get("physics") or {}).get("step_ms", 2.0))
    except (OSError, ValueError, TypeError, AttributeError):
        step_ms = 2.0  # (the scene's own errors are named when it is loaded)
    if step_ms > 0 and not _whole(frame_ms / step_ms):
        raise ConfigError(f"{where}: frame_ms {frame_ms:g} is not a whole number of the scene's physics steps "
                          f"({step_ms:g} ms)")
    if not _whole(TICK_MS / frame_ms):
        raise ConfigError(f"{where}: frame_ms {frame_ms:g} does not divide the skill manager's tick of {TICK_MS:g} ms "
                          f"(frames of 2, 4, 5, 8, 10, 20 or 40 ms)")
    if not _whole(1000.0 / (fps * frame_ms)):
        rates = [f"{1000.0 / (k * frame_ms):g}" for k in range(1, 6)]
        raise ConfigError(f"{where}: fps {fps:g} is not a whole number of {frame_ms:g} ms frames per row: rows come "
                          f"every whole frame ({', '.join(rates)}, ... fps)")


def episode_seed(seed: int, index: int) -> int:
    """Episode `index`'s seed from the run's seed: the same on every machine, and any
    episode can be run alone from it (``skillbus generate --episode``).

    >>> episode_seed(7, 0), episode_seed(7, 1) != episode_seed(7, 0)
    (7936772520358626759, True)
    """
    import hashlib
    h = hashlib.sha256(f"skillbus-episode:{seed}:{index}".encode()).digest()
    return int.from_bytes(h[:8], "big") >> 1


def as_dict(cfg: GenerateConfig) -> dict[str, Any]:
    return {"config": str(cfg.path), "scene": str(cfg.scene), "skills": cfg.skills, "instruction": cfg.instruction,
            "fps": cfg.fps, "frame_ms": cfg.frame_ms, "randomize": cfg.randomize}
