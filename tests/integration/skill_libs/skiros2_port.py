"""Runs a SkiROS2 skill module with only its import lines changed: the module's text is
read from its upstream git repository (a local bare copy, not kept in this repository),
each import of a SkiROS2 or ROS module is replaced by skillbus's, every other line is
left as it is, and the result runs in the namespace of the test library that asked for
it (so its skill classes are that library's).

The copies are looked for under $SKILLBUS_SKIROS2_MIRROR (default /work/.mirror), as
<owner>+<name>/repo: e.g. /work/.mirror/RVMI+skiros2_std_lib/repo. Without one the
library cannot load: UpstreamMissing (an ImportError) names the path.
"""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

MIRROR_ENV = "SKILLBUS_SKIROS2_MIRROR"

# The module each SkiROS2 (or ROS) import names -> what a skillbus user writes instead.
MODULES = {
    "skiros2_skill.core.skill": "skillbus.skill",
    "skiros2_skill.core.processors": "skillbus.skill",
    "skiros2_common.core.primitive": "skillbus.skill",
    "skiros2_common.core.abstract_skill": "skillbus.skill",
    "skiros2_common.core.params": "skillbus.skill",
    "skiros2_common.core.conditions": "skillbus.skill",
    "skiros2_common.core.world_element": "skillbus.skill",
}
PLAIN_IMPORTS = {"import rospy": "from skillbus.skill import ros_clock as rospy"}
FOREIGN = re.compile(r"^\s*(from|import)\s+(skiros2_\w*|rospy|rclpy|actionlib\w*|\w+_msgs)\b")


class UpstreamMissing(ImportError):
    pass


def mirror() -> Path:
    return Path(os.environ.get(MIRROR_ENV, "/work/.mirror"))


def upstream_source(repo: str, path: str, rev: str = "master") -> str:
    """The text of `path` at `rev` in the upstream repository `repo` ("owner+name")."""
    git_dir = mirror() / repo / "repo"
    if not git_dir.is_dir():
        raise UpstreamMissing(f"no copy of {repo.replace('+', '/')} at {git_dir} (set ${MIRROR_ENV} to the folder "
                              f"that holds <owner>+<name>/repo)")
    r = subprocess.run(["git", "--git-dir", str(git_dir), "show", f"{rev}:{path}"], capture_output=True, text=True)
    if r.returncode != 0:
        raise UpstreamMissing(f"{repo.replace('+', '/')}: no {path} at {rev}: {r.stderr.strip()}")
    return r.stdout


def port_line(line: str) -> str:
    """One line as a skillbus user writes it: an import of a SkiROS2 module names
    skillbus's; any other line is unchanged. A SkiROS2 or ROS import with no skillbus
    counterpart raises ImportError naming it."""
    stripped = line.strip()
    if stripped in PLAIN_IMPORTS:
        return line[: len(line) - len(line.lstrip())] + PLAIN_IMPORTS[stripped]
    m = re.match(r"^(\s*)from\s+([\w.]+)\s+import\s+(.*)$", line)
    if m and m.group(2) in MODULES:
        return f"{m.group(1)}from {MODULES[m.group(2)]} import {m.group(3)}"
    if FOREIGN.match(line):
        raise ImportError(f"no skillbus counterpart for {stripped!r}")
    return line


def port(source: str) -> str:
    return "\n".join(port_line(line) for line in source.split("\n"))


def load_upstream(namespace: dict, repo: str, paths: list[str], rev: str = "master") -> list[str]:
    """Runs the ported modules, in order, in `namespace` (a library module's globals);
    returns the names of the upstream files it ran."""
    for path in paths:
        name = f"{repo.replace('+', '/')}:{path}"
        exec(compile(port(upstream_source(repo, path, rev)), name, "exec"), namespace)
    return paths
