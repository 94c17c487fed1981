"""Manipulation-command skills in InternDataEngine's style (docs/manip.md): ManipSkill,
@register_skill, YAML configuration, and the executor that runs their command lists
inside skill-manager primitives."""

from skillbus.manip.command import ACTIONS, ManipCommand
from skillbus.manip.registry import SKILLS, get_skill, register_skill, skill_key
from skillbus.manip.skill import ManipSkill

__all__ = ["ACTIONS", "ManipCommand", "ManipSkill", "SKILLS", "get_skill", "register_skill", "skill_key"]
