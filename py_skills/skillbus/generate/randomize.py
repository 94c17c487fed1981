"""A randomized scene for one episode, from its seed alone (Python's random.Random:
Mersenne Twister, the same sequence on every platform for an integer seed).

``randomize.objects.NAME``: ``x``, ``y`` ([lo, hi] m, world: the object's centre), ``yaw``
([lo, hi] rad, about the vertical), ``size`` ([lo, hi] m: a box's edges, scaled alike;
its bottom stays where it was), ``colors`` (a list: one is chosen; the physics does not
draw, the dataset records it). ``randomize.articulated.NAME``: ``x``, ``y``, ``yaw`` as
offsets from the scene's pose. ``randomize.choose_articulated``: a list of articulated
objects' names, of which one is kept (the others are taken out of the scene).

>>> doc = {"objects": [{"name": "red", "shape": "box", "size": [0.05, 0.05, 0.05], "pose": [0.4, 0, 0.425, 0, 0, 0, 1]}]}
>>> a, info = randomized(doc, {"objects": {"red": {"x": [0.4, 0.5]}}}, 3)
>>> b, _ = randomized(doc, {"objects": {"red": {"x": [0.4, 0.5]}}}, 3)
>>> a == b and 0.4 <= a["objects"][0]["pose"][0] <= 0.5
True
"""

from __future__ import annotations

import copy
import math
import random
from typing import Any

from skillbus.generate.config import ConfigError


def _range(spec: dict, key: str, where: str) -> tuple[float, float] | None:
    v = spec.get(key)
    if v is None:
        return None
    if not (isinstance(v, list) and len(v) == 2 and all(isinstance(x, (int, float)) for x in v) and v[0] <= v[1]):
        raise ConfigError(f"randomize.{where}.{key} must be [lo, hi] with lo <= hi, not {v!r}")
    return float(v[0]), float(v[1])


def _yawed(q: list[float], yaw: float) -> list[float]:
    from skillbus.quat import qmul
    return list(qmul((0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)), tuple(q)))  # type: ignore[arg-type]


def randomized(doc: dict[str, Any], spec: dict[str, Any], seed: int) -> tuple[dict[str, Any], dict[str, Any]]:
    """The scene document changed by `spec`, and what was chosen (for the dataset)."""
    rng = random.Random(seed)
    out = copy.deepcopy(doc)
    info: dict[str, Any] = {"objects": {}, "articulated": {}}
    objects = {o["name"]: o for o in out.get("objects", [])}
    for name, s in sorted((spec.get("objects") or {}).items()):
        if name not in objects:
            raise ConfigError(f"randomize.objects.{name}: the scene has no object {name!r} "
                              f"(it has: {', '.join(sorted(objects)) or 'none'})")
        o, chosen = objects[name], {}
        pose = list(o.get("pose", [0, 0, 0, 0, 0, 0, 1]))
        for i, key in enumerate(("x", "y")):
            r = _range(s, key, f"objects.{name}")
            if r is not None:
                pose[i] = chosen[key] = rng.uniform(*r)
        r = _range(s, "yaw", f"objects.{name}")
        if r is not None:
            chosen["yaw"] = rng.uniform(*r)
            pose[3:7] = _yawed(pose[3:7], chosen["yaw"])
        r = _range(s, "size", f"objects.{name}")
        if r is not None:
            if o.get("shape") != "box":
                raise ConfigError(f"randomize.objects.{name}.size: only boxes can be resized")
            new = rng.uniform(*r)
            scale = new / max(o["size"])
            old_h = o["size"][2]
            o["size"] = [e * scale for e in o["size"]]
            pose[2] += (o["size"][2] - old_h) / 2  # its bottom stays
            chosen["size"] = new
        colors = s.get("colors")
        if colors:
            if not isinstance(colors, list):
                raise ConfigError(f"randomize.objects.{name}.colors must be a list")
            o["color"] = chosen["color"] = str(rng.choice(colors))
        o["pose"] = pose
        info["objects"][name] = chosen
    arts = {a["name"]: a for a in out.get("articulated", [])}
    keep = spec.get("choose_articulated")
    if keep:
        missing = [k for k in keep if k not in arts]
        if missing:
            raise ConfigError(f"randomize.choose_articulated: the scene has no articulated object {missing[0]!r}")
        chosen_art = rng.choice(list(keep))
        out["articulated"] = [a for a in out.get("articulated", []) if a["name"] == chosen_art or a["name"] not in keep]
        info["articulated_chosen"] = chosen_art
        arts = {a["name"]: a for a in out["articulated"]}
    for name, s in sorted((spec.get("articulated") or {}).items()):
        if name not in arts:
            continue  # (taken out by choose_articulated)
        a, chosen = arts[name], {}
        pose = list(a.get("pose", [0, 0, 0, 0, 0, 0, 1]))
        for i, key in enumerate(("x", "y")):
            r = _range(s, key, f"articulated.{name}")
            if r is not None:
                chosen[key] = rng.uniform(*r)
                pose[i] += chosen[key]
        r = _range(s, "yaw", f"articulated.{name}")
        if r is not None:
            chosen["yaw"] = rng.uniform(*r)
            pose[3:7] = _yawed(pose[3:7], chosen["yaw"])
        a["pose"] = pose
        info["articulated"][name] = chosen
    return out, info
