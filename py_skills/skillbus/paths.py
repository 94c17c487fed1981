"""Where the built C++ programs and generated files are."""

from __future__ import annotations

import os
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]


def build_dir() -> Path:
    return Path(os.environ.get("SKILLBUS_BUILD_DIR", REPO_ROOT / "build"))


# Each C++ program, by the folder of the build tree it is built in.
_PROGRAMS = {
    "sb_clock": "common",
    "sb_demo_participant": "common",
    "sb_rpc_counter": "common",
    "sim_server": "sim_server",
}


def demo_scene() -> Path:
    return REPO_ROOT / "deploy" / "scenes" / "demo.scene.json"


def binary(name: str) -> Path:
    path = build_dir() / _PROGRAMS.get(name, "") / name
    if not path.exists():
        raise FileNotFoundError(f"{path} does not exist: run `make build` first")
    return path


def types_jar() -> Path:
    return build_dir() / "gen" / "skillbus_msgs.jar"
