"""Channel names, shared and per robot (docs/transport.md, "Several robots").

Several robots share one bus: a robot's own channels (its arm, camera, fingers, skill
manager, skill processes, motion service, CAN sync) are ``<robot>/<name>`` for the
process's robot, while the world model, the lockstep, the physics server's control and
the log are shared. ``$SKILLBUS_NAMESPACE`` goes in front of everything (a whole system
apart on one bus). The C++ side (common/src/channels.cpp) names them the same way.

>>> robot_channel("SB_ROBOT_ARM_CMD", "r2"), robot_channel("SB_WM_REQ", "r2")
('r2/SB_ROBOT_ARM_CMD', 'SB_WM_REQ')
>>> robot_scoped("SB_SKPROC_SKILLS_REQ"), robot_scoped("SB_MANAGERS")
(True, False)
>>> valid_robot_name("r2"), valid_robot_name("r/2"), valid_robot_name("2r")
(True, False, False)
"""

from __future__ import annotations

import os
import re

_SCOPED_PREFIXES = ("SB_ROBOT_", "SB_SKILL_", "SB_SKPROC_", "SB_SKTREE_", "SB_MOTION_", "SB_CAN_")
_SCOPED = frozenset({"SB_SIM_STATE", "SB_SIM_GRIPPER_CMD", "SB_SIM_CMD_REPLY", "SB_SIM_ATTACH"})
_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
MAX_ROBOT_NAME = 24  # LCM's channel names end at 63 bytes: NAME/ and the longest robot channel must fit
MAX_CHANNEL = 63  # LCM_MAX_CHANNEL_NAME_LENGTH: DDS allows more, but one name must work on both

_robot: str | None = None  # set_robot(); None: $SKILLBUS_ROBOT


def robot_scoped(name: str) -> bool:
    """Whether `name` is one of a robot's own channels (else shared by all robots)."""
    return name.startswith(_SCOPED_PREFIXES) or name in _SCOPED


def expand_area(process: str) -> str:
    """The RPC area where skill process `process` expands its compounds for anyone holding
    the bus key (`skillbus tree SKILL`). Not the process's own area ("SKPROC_" + NAME): the
    system's policy lets only the manager send there, since that is where skills are
    ticked. As long as the process's own area, so that every process name fits both.

    >>> expand_area("skills"), len(expand_area("skills")) == len("SKPROC_SKILLS")
    ('SKTREE_SKILLS', True)
    """
    return "SKTREE_" + process.upper()


def valid_robot_name(robot: str) -> bool:
    """A letter, then letters, digits or _: it becomes part of channel and DDS topic names."""
    return len(robot) <= MAX_ROBOT_NAME and bool(_NAME.fullmatch(robot))


def set_robot(robot: str) -> None:
    """This process's robot (a program's --robot; "" for none, whatever the environment
    says). Raises ValueError for a name that cannot be part of a channel name."""
    global _robot
    if robot and not valid_robot_name(robot):
        raise ValueError(f"robot name {robot!r}: a letter, then letters, digits or _, at most {MAX_ROBOT_NAME} "
                         f"(it becomes part of channel names)")
    _robot = robot


def current_robot() -> str:
    """The process's robot: set_robot(), else $SKILLBUS_ROBOT, else ""."""
    return _robot if _robot is not None else os.environ.get("SKILLBUS_ROBOT", "")


def _bytes(s: str) -> int:
    """Its length in bytes, as LCM and the C++ side count (an environment's undecodable
    bytes as they were)."""
    return len(s.encode("utf-8", "surrogateescape"))


def too_long(name: str) -> str:
    """Why `name` cannot be a channel ("" when it can): LCM ends channel names at 63
    bytes, and a longer one fails only later, and far from its cause (it subscribes and
    never hears a message; its publish is refused)."""
    size = _bytes(name)
    if size <= MAX_CHANNEL:
        return ""
    return f"channel name '{name}' is {size} bytes: LCM ends channel names at {MAX_CHANNEL}"


_TOPIC = re.compile(r"[A-Za-z_][A-Za-z0-9_/]*")  # what a DDS topic name may be (Cyclone 0.10)


def bad_characters(name: str) -> str:
    """Why `name` cannot be a channel on DDS ("" when it can): Cyclone DDS (the C++ side's
    0.10) takes letters, digits, _ and / in a topic name, not starting with a digit; LCM
    takes anything. One name must work on both transports."""
    if _TOPIC.fullmatch(name):
        return ""
    bad = sorted({c for c in name if not (c.isascii() and (c.isalnum() or c in "_/"))})
    what = (f"{', '.join(repr(c) for c in bad)} cannot be in a channel name" if bad
            else "a channel name cannot start with a digit")
    return f"channel name {name!r}: {what} (letters, digits, _ and /: DDS topics allow no more)"


# Names already made, by (namespace, robot, name): processes name channels every frame (a
# lockstep message's channel, a CAN link's announcement), and checking a name costs a
# regular expression and an encoding (2.7 us a call). Keyed by the environment as it is
# at each call, so a changed $SKILLBUS_NAMESPACE still counts. Bounded.
_MADE: dict[tuple[str, str, str], str] = {}
_MADE_MAX = 4096


def robot_channel(name: str, robot: str) -> str:
    """`name` for an explicit robot ("" for none). Raises ValueError for a name longer
    than a channel may be, or with characters a DDS topic refuses, saying which part
    made it so."""
    prefix = os.environ.get("SKILLBUS_NAMESPACE", "")
    key = (prefix, robot, name)
    made = _MADE.get(key)
    if made is not None:
        return made
    out = _make_channel(prefix, name, robot)
    if len(_MADE) < _MADE_MAX:
        _MADE[key] = out
    return out


def _make_channel(prefix: str, name: str, robot: str) -> str:
    mine = robot if robot and robot_scoped(name) else ""
    out = prefix + (f"{mine}/" if mine else "") + name
    why = bad_characters(out)
    if why:
        raise ValueError(why + (f" ($SKILLBUS_NAMESPACE is {prefix!r})" if prefix and bad_characters(prefix + "X") else ""))
    why = too_long(out)
    if why:
        parts = [f"$SKILLBUS_NAMESPACE '{prefix}' takes {_bytes(prefix)}"] if prefix else []
        if mine:
            parts.append(f"robot {mine} takes {_bytes(mine) + 1}")
        parts.append(f"{name} takes {_bytes(name)}")
        raise ValueError(f"{why} ({', '.join(parts)}): shorten the name it is made of")
    return out


def channel(name: str) -> str:
    """`name` as this process names it: behind $SKILLBUS_NAMESPACE, and under the
    process's robot when it is one of a robot's own channels."""
    return robot_channel(name, current_robot())
