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
    return GenerateConfig(path=path, scene=scene, skills=skills,
                          instruction=str(data.get("instruction") or f"task of {path.stem}"),
                          fps=_number(data, "fps", 10.0, 0.1, where), max_sim_s=_number(data, "max_sim_s", 240.0, 1, where),
                          retries=retries, cameras=cameras, frame_ms=_number(data, "frame_ms", 20.0, 1, where), randomize=randomize,
                          arm=str(data.get("arm", "arm")), gripper=str(data.get("gripper", "gripper")))


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
