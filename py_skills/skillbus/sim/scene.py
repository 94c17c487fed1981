"""Scene files (docs/scene.md) on the Python side: read one, and turn it into the world
model's Turtle scene so that the world model (belief) and the physics server (truth)
start from the same file.

There is one reader and one Turtle writer, in C++: the program ``sb_scene``
(sim_server/scene), built on the library the physics server and the motion server read
scene files with. This module runs it: ``load`` is ``sb_scene check FILE --json`` (the
physics server's checks; the scene normalized: defaults filled in, URDF paths absolute,
unit quaternions), ``to_turtle`` is ``sb_scene turtle`` (element ids in the file's order,
poses relative to the container, labels escaped by the world model's Turtle writer). A
scene that does not pass raises SceneError with the program's message, which names the
file and the field.
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

from skillbus import paths
from skillbus.quat import relative

_PREFIX = "sb_scene: error: "


class SceneError(ValueError):
    pass


def relative_pose(parent: list[float], child: list[float]) -> list[float]:
    """child's pose in parent's frame (both x y z qx qy qz qw in the world frame).

    >>> relative_pose([1, 0, 0, 0, 0, 0, 1], [1.5, 0.2, 0.5, 0, 0, 0, 1])
    [0.5, 0.2, 0.5, 0, 0, 0, 1]
    """
    p, q = relative(parent, child)
    return [*p, *q]


def _run(*args: str, stdin: str | None = None) -> str:
    """sb_scene's standard output; SceneError with its message when it refuses."""
    r = subprocess.run([str(paths.binary("sb_scene")), *args], input=stdin, capture_output=True, text=True,
                       timeout=60)
    if r.returncode != 0:
        lines = r.stderr.strip().splitlines() or [f"sb_scene {args[0]} ended with exit code {r.returncode}"]
        raise SceneError(lines[-1].removeprefix(_PREFIX))
    return r.stdout


def check(path: str | Path) -> str:
    """Checks a scene file; the program's one line ("FILE: a valid scene (...)")."""
    return _run("check", str(path)).rstrip("\n")


def load(path: str | Path) -> dict[str, Any]:
    """The scene file at `path`, checked and normalized (a scene document again, with
    every default filled in and URDF paths absolute, so it can be changed and written
    anywhere)."""
    return json.loads(_run("check", str(path), "--json"))


def element_ids(path: str | Path) -> dict[str, str]:
    """The world model's element ids of the scene file at `path`, by label
    ({"table": "skiros:Table-1", ...}): what a task names the scene's things by."""
    return json.loads(_run("ids", str(path)))


def to_turtle(scene: dict[str, Any]) -> str:
    """The world model's Turtle scene for a scene document (from `load`, perhaps changed;
    relative URDF paths in it start from the current folder). Checked as a file is."""
    return _run("turtle", "-", stdin=json.dumps(scene))


def save(doc: dict[str, Any], path: str | Path, source: str | Path) -> Path:
    """Writes a scene document (read from `source`, perhaps changed) to `path`, with its
    URDF paths made absolute, since they are relative to the file they came from."""
    base = Path(source).resolve().parent
    doc = json.loads(json.dumps(doc))
    for part in [doc.get("robot", {}), *doc.get("robots", []), *doc.get("fixtures", []), *doc.get("obstacles", []),
                 *doc.get("articulated", [])]:
        if isinstance(part, dict) and part.get("urdf"):
            part["urdf"] = str((base / part["urdf"]).resolve())
    Path(path).write_text(json.dumps(doc, indent=1))
    return Path(path)
