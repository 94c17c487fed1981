"""``ManipTask``: a task file's skills (skillbus.manip.config.load_task) as one compound
skill of the skill manager, its children in a SerialStar (each runs once, in order; the
first failure fails the task). So a YAML task runs, shows and stops like any task::

    skillbus run ManipTask -p Task=deploy/tasks/drawer_pick_place.yaml \\
        -p Arm=skiros:Arm-6 -p Gripper=skiros:Gripper-5

Each entry's element parameters (the skill's ``elements``: Object, Location) name a
world-model element by id (``skiros:Cube-2``) or by label (``red``, ``cabinet/drawer_joint``);
everything else goes to the child's configuration (its ``Config`` parameter, as YAML).
"""

from __future__ import annotations

import yaml

from skillbus.manip import config as manip_config
from skillbus.manip.primitive import camel
from skillbus.manip.registry import get_skill
from skillbus.skill import Element, ParamTypes, SerialStar, SkillBase, SkillDescription


class ManipTask(SkillDescription):
    def createDescription(self):
        self.addParam("Arm", Element("skiros:Arm"), ParamTypes.Required)
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Optional)
        self.addParam("Task", "", ParamTypes.Required,
                      description="a task file (.yaml) with a skills: list, or that YAML itself")


def element_of(wmi, name: str):
    """The world model's element for an id or a label; ValueError naming the name."""
    if wmi is None:
        raise ValueError(f"{name!r}: this skill process has no world model (--world-model)")
    try:
        return wmi.get_element(name)
    except Exception:
        pass
    found = [e for e in wmi.get_elements() if e.label == name]
    if len(found) != 1:
        raise ValueError(f"{name!r} names {'no' if not found else 'more than one'} element of the world model")
    return found[0]


class manip_task(SkillBase):
    def createDescription(self):
        self.setDescription(ManipTask(), "manip_task")

    def expand(self, skill):
        path = self.params["Task"].value
        entries = manip_config.load_task(path)
        children = []
        for i, entry in enumerate(entries):
            entry = dict(entry)
            key = entry.pop("name")
            try:
                cls = get_skill(key)
            except KeyError as e:
                raise ValueError(f"{path}: skills[{i}]: {e.args[0]}") from None
            for own in ("Arm", "Gripper"):
                if own in entry:  # (it went into the Config, unread: the task's arm moved)
                    raise ValueError(f"{path}: skills[{i}] ({key}): {own} is the task's for every entry (give it to "
                                     f"ManipTask), not an entry's")
            refused = cls.keys_refused(entry)
            if refused:
                raise ValueError(f"{path}: skills[{i}] ({key}): {refused}")
            specify = {}
            for pname in list(cls.elements) + list(cls.optional_elements):
                if pname in entry:
                    try:
                        specify[pname] = element_of(self.wmi, str(entry.pop(pname)))
                    except ValueError as e:
                        raise ValueError(f"{path}: skills[{i}] ({key}): {pname}: {e}") from None
                elif pname in cls.elements:
                    raise ValueError(f"{path}: skills[{i}] ({key}) needs {pname}")
            if entry:
                specify["Config"] = yaml.safe_dump(entry, sort_keys=True)
            children.append(self.skill(f"Manip{camel(key)}", "", specify=specify))
        skill(self.skill(SerialStar())(*children))
