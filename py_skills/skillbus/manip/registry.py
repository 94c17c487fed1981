"""The registry of manipulation-command skills: ``@register_skill`` on a ManipSkill
subclass files it under a key made from its class name (``GotoPose`` and ``Goto_Pose``
are both ``goto_pose``), the name a YAML task uses.

>>> skill_key("GotoPose"), skill_key("Gripper_Action"), skill_key("Pick")
('goto_pose', 'gripper_action', 'pick')
"""

from __future__ import annotations

import re
from typing import Any

SKILLS: dict[str, type] = {}


def skill_key(class_name: str) -> str:
    words = re.sub(r"([A-Z0-9]+)", r" \1", class_name).replace("_", " ").split()
    return "_".join(words).lower()


def register_skill(cls: type) -> type:
    """Class decorator: registers a ManipSkill subclass under skill_key(its name). A second
    class with the same key is refused (two skills answering to one name in a YAML task
    would run whichever was imported last)."""
    from skillbus.manip.skill import ManipSkill
    if not (isinstance(cls, type) and issubclass(cls, ManipSkill)):
        raise TypeError(f"register_skill: {cls!r} is not a ManipSkill subclass")
    key = skill_key(cls.__name__)
    old = SKILLS.get(key)
    if old is not None and old is not cls and (old.__module__, old.__qualname__) != (cls.__module__, cls.__qualname__):
        raise ValueError(f"register_skill: {key!r} is taken by {old.__module__}.{old.__qualname__}")
    SKILLS[key] = cls
    cls.key = key
    return cls


def get_skill(key: str) -> Any:
    """The class registered under `key`; KeyError naming the registered ones."""
    try:
        return SKILLS[key]
    except KeyError:
        raise KeyError(f"no manipulation skill {key!r} (registered: {', '.join(sorted(SKILLS)) or 'none'})") from None
