"""One entry of a manipulation command list (``manip_list``), as InternDataEngine's skills
build them: a target pose of the end effector in the arm's base frame, an action to apply
once the arm is there, and its parameters::

    (p_base_ee, q_base_ee, "close_gripper", {})            # p: x y z (m), q: w x y z
    (p_base_ee, q_base_ee, "dummy_forward", {"motion": "linear"}, 0.3)   # 5th: speed

Poses may be numpy arrays or plain sequences. The parameters a command understands:

- ``motion``: ``"free"`` (joint-space, around obstacles; the default), ``"linear"`` (a
  straight line of the tool), ``"joints"`` (to ``joints``, a mapping joint -> position;
  the pose is then not used) or ``"none"`` (no motion: the action only);
- ``object``: the object of ``attach_obj``/``detach_obj`` (its scene name);
- ``frames``: how many frames ``wait`` waits;
- ``width``: for ``open_gripper``, the opening in m (default fully open);
- ``fallback``: ``"free"`` lets a ``linear`` move whose plan was refused be planned in
  joint space on the next try (short steps of a handle's path, where a straight line may
  need a wrist flip half way);
- ``settle_rad``: how close (rad, every arm joint) the arm must come to the end of the
  trajectory before the action (default 0.01; a move that drags a door or a drawer may
  end a little short, held back by the mechanism).

>>> c = ManipCommand.from_entry(([0.4, 0, 0.5], [0, 1, 0, 0], "close_gripper", {}))
>>> c.action, c.position, c.quaternion
('close_gripper', (0.4, 0.0, 0.5), (0.0, 1.0, 0.0, 0.0))
>>> ManipCommand.from_entry(([0.4, 0, 0.5], [0, 0, 0, 0], "close_gripper", {}))
Traceback (most recent call last):
...
ValueError: manip command: the quaternion (w x y z) is zero
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from typing import Any, Sequence

ACTIONS = ("dummy_forward", "open_gripper", "close_gripper", "attach_obj", "detach_obj", "wait")
MOTIONS = ("free", "linear", "joints", "none")


def _vector(value: Any, n: int, what: str) -> tuple[float, ...]:
    try:
        out = tuple(float(x) for x in value)
    except (TypeError, ValueError):
        raise ValueError(f"manip command: {what} must be {n} numbers, not {value!r}") from None
    if len(out) != n:
        raise ValueError(f"manip command: {what} must be {n} numbers, not {len(out)}")
    if not all(math.isfinite(x) for x in out):
        raise ValueError(f"manip command: {what} has a value that is not finite: {out}")
    return out


def _finite(v: Any) -> bool:
    """A finite number (numpy's too), not a bool."""
    return isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)


def _number(params: dict, key: str, low: float, low_ok: bool) -> None:
    """params[key], when given, is a finite number above `low` (or at it, `low_ok`)."""
    if key not in params or params[key] is None:
        return
    v = params[key]
    ok = _finite(v) and (v > low or (low_ok and v == low))
    if not ok:
        raise ValueError(f"manip command: params[{key!r}] must be a finite number {'>=' if low_ok else '>'} {low:g}, "
                         f"not {v!r}")


def _check_params(params: dict) -> None:
    """The parameters a command understands, checked when the list is built: a NaN width or
    a negative wait is named before the arm moves, not found when its command comes."""
    _number(params, "width", 0.0, True)
    _number(params, "settle_rad", 0.0, False)
    frames = params.get("frames")
    if frames is not None and (not isinstance(frames, numbers.Integral) or isinstance(frames, bool) or frames < 0):
        raise ValueError(f"manip command: params['frames'] must be a whole number >= 0, not {frames!r}")
    if params.get("fallback") not in (None, "free"):
        raise ValueError(f"manip command: params['fallback'] can only be 'free', not {params['fallback']!r}")
    if params.get("motion") == "joints":
        for name, q in params["joints"].items():
            if not _finite(q):
                raise ValueError(f"manip command: params['joints'][{name!r}] must be a finite number, not {q!r}")


@dataclass(frozen=True)
class ManipCommand:
    position: tuple[float, float, float]            # end effector in the arm's base frame, m
    quaternion: tuple[float, float, float, float]   # w x y z, unit
    action: str = "dummy_forward"
    params: dict = field(default_factory=dict)
    speed: float | None = None                      # fraction of the joints' velocity limits

    @classmethod
    def from_entry(cls, entry: Any) -> "ManipCommand":
        """A command from a manip_list entry: a ManipCommand, or a tuple (p, q, action,
        params[, speed]). Raises ValueError naming what is wrong."""
        if isinstance(entry, ManipCommand):
            return entry
        if not isinstance(entry, (tuple, list)) or not 3 <= len(entry) <= 5:
            raise ValueError(f"manip command: expected (p, q, action, params[, speed]), not {entry!r}")
        p = _vector(entry[0], 3, "the position")
        q = _vector(entry[1], 4, "the quaternion (w x y z)")
        norm = math.sqrt(sum(x * x for x in q))
        if norm < 1e-9:
            raise ValueError("manip command: the quaternion (w x y z) is zero")
        q = tuple(x / norm for x in q)
        action = entry[2]
        if action not in ACTIONS:
            raise ValueError(f"manip command: unknown action {action!r} (one of {', '.join(ACTIONS)})")
        params = dict(entry[3]) if len(entry) > 3 and entry[3] is not None else {}
        motion = params.get("motion", "free")
        if motion not in MOTIONS:
            raise ValueError(f"manip command: motion {motion!r} is not one of {', '.join(MOTIONS)}")
        if motion == "joints" and not isinstance(params.get("joints"), dict):
            raise ValueError("manip command: motion 'joints' needs params['joints'], a mapping joint -> position")
        if action in ("attach_obj", "detach_obj") and action == "attach_obj" and not params.get("object"):
            raise ValueError("manip command: attach_obj needs params['object'], the object's name")
        _check_params(params)
        speed = entry[4] if len(entry) > 4 else None
        if speed is not None:
            speed = float(speed)
            if not 0 < speed <= 1:
                raise ValueError(f"manip command: speed {speed} must be in (0, 1] (a fraction of the joint limits)")
        return cls(p, q, action, params, speed)  # type: ignore[arg-type]

    @property
    def motion(self) -> str:
        return self.params.get("motion", "free")

    def describe(self) -> str:
        p = " ".join(f"{x:.3f}" for x in self.position)
        return f"{self.action} at ({p}) [{self.motion}]"


def as_commands(entries: Sequence[Any]) -> list[ManipCommand]:
    return [ManipCommand.from_entry(e) for e in entries]
