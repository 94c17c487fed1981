"""Where the built C++ programs and generated files are."""

from __future__ import annotations

import os
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]


# A unix socket's path must fit sockaddr_un (108 bytes with its NUL).
SOCKET_PATH_MAX = 100


def socket_path(folder: str | Path, name: str) -> Path:
    """Where a unix socket named `name` for `folder` goes: in the folder when the path
    fits a unix socket's address, else in a short folder in the temporary folder made
    from the folder's name (the same for every process that asks), under its own name. A run folder deep in a
    tree (a test's, an episode's) would otherwise make the CAN hub or supervisord fail
    with "AF_UNIX path too long".

    >>> str(socket_path("/tmp/run", "gripper0.sock"))
    '/tmp/run/gripper0.sock'
    >>> p = socket_path("/tmp/" + "d" * 120, "gripper0.sock"); len(str(p)) <= SOCKET_PATH_MAX, p.name
    (True, 'gripper0.sock')
    """
    import hashlib
    import tempfile
    path = Path(folder) / name
    if len(os.fsencode(str(path))) <= SOCKET_PATH_MAX:
        return path
    tag = hashlib.sha256(os.fsencode(str(Path(folder).resolve()))).hexdigest()[:16]
    # A folder of its own keeps the socket's name: the CAN channel is named by it on the
    # bus, so a run's messages (and its session digest) do not depend on where it ran.
    short = Path(tempfile.gettempdir()) / f"skillbus-{tag}"
    short.mkdir(mode=0o700, exist_ok=True)
    return short / name


def build_dir() -> Path:
    return Path(os.environ.get("SKILLBUS_BUILD_DIR", REPO_ROOT / "build"))


# Each C++ program, by the folder of the build tree it is built in.
_PROGRAMS = {
    "sb_clock": "common",
    "sb_demo_participant": "common",
    "sb_rpc_counter": "common",
    "wm_server": "wm_server",
    "skill_mgr": "skill_mgr",
    "sim_server": "sim_server",
    "sb_scene": "sim_server",
    "motion_server": "motion_server",
    "map_server": "map_server",
    "codec_peer": "tests/cpp",
    "bus_junk_peer": "tests/cpp",
    "bus_late_reader_peer": "tests/cpp",
}


def demo_scene() -> Path:
    return REPO_ROOT / "deploy" / "scenes" / "demo.scene.json"


def binary(name: str) -> Path:
    """The built program `name` (absolute). KeyError for a name that is no program of the
    build, FileNotFoundError when it has not been built.

    >>> binary("wm_server").relative_to(build_dir().resolve()).as_posix()
    'wm_server/wm_server'
    >>> binary("wm")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
        ...
    KeyError: "no program 'wm' in the build; the programs: bus_junk_peer, bus_late_reader_peer, ..."
    """
    if name not in _PROGRAMS:
        raise KeyError(f"no program {name!r} in the build; the programs: {', '.join(sorted(_PROGRAMS))}")
    path = build_dir().resolve() / _PROGRAMS[name] / name
    if not path.is_file():
        raise FileNotFoundError(f"{path} does not exist: run `make build` first")
    return path


def lcm_logger() -> Path:
    """The lcm-logger program of the lcm wheel itself: its console script is a Python
    process that runs this one as a child (two processes, and an interpreter's start, for
    one logger)."""
    import lcm
    exe = Path(getattr(lcm, "LCM_BIN_DIR", Path(lcm.__file__).resolve().parents[1] / "bin")) / "lcm-logger"
    if not exe.is_file():
        raise FileNotFoundError(f"{exe} does not exist: the lcm wheel is not installed as expected")
    return exe


def types_jar() -> Path:
    return build_dir() / "gen" / "skillbus_msgs.jar"
