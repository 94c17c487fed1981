"""What Locate writes when the skill process has a depth camera: the objects the camera
sees on the Location, matched to the world model's (docs/perception.md, "Locate").

A detection is matched to the world model's object on the Location nearest to it (its
position in the world model: the last one located, or the scene's), nearest pairs first,
within `MATCH_RADIUS`; if the object has a Size, the detection's sides must agree with it
within `SIZE_TOLERANCE`. What is left unmatched is a new object.
"""

from __future__ import annotations

import dataclasses
import math

from skillbus.perception.segment import Detection

MATCH_RADIUS = 0.10    # m: farther than this, a detection is another object
SIZE_TOLERANCE = 0.01  # m: a detection's length and width against the object's Size


@dataclasses.dataclass
class Known:
    id: str
    position: tuple[float, float, float]
    size: float | None  # the world model's Size (a cube's side), if it has one


@dataclasses.dataclass
class Matched:
    matches: list[tuple[Known, Detection]]
    new: list[Detection]
    unseen: list[Known]


def size_agrees(k: Known, d: Detection) -> bool:
    return k.size is None or (abs(d.size[0] - k.size) <= SIZE_TOLERANCE and abs(d.size[1] - k.size) <= SIZE_TOLERANCE)


def match(known: list[Known], detections: list[Detection]) -> Matched:
    """Nearest pairs first (ties by id, then by detection order): the same inputs give the
    same matches."""
    pairs = sorted((math.dist(k.position[:2], d.position[:2]), k.id, j)
                   for k in known for j, d in enumerate(detections)
                   if math.dist(k.position[:2], d.position[:2]) <= MATCH_RADIUS and size_agrees(k, d))
    by_id = {k.id: k for k in known}
    used_k: set[str] = set()
    used_d: set[int] = set()
    out: list[tuple[Known, Detection]] = []
    for _, kid, j in pairs:
        if kid in used_k or j in used_d:
            continue
        used_k.add(kid)
        used_d.add(j)
        out.append((by_id[kid], detections[j]))
    out.sort(key=lambda m: m[0].id)
    return Matched(out, [d for j, d in enumerate(detections) if j not in used_d],
                   [k for k in known if k.id not in used_k])
