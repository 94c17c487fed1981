"""The manipulation-command skill family as a skill library of the skill process::

    skillbus skills-process --name skills --library skillbus.manip.library --arm --gripper ... \\
        --interface articulation=skillbus.robot.articulation --interface attach=skillbus.sim.attach

Every registered manipulation skill (the family's, and any other module's registered
before this one is imported) becomes ``Manip<Name>`` (e.g. ManipPick, ManipOpen,
ManipGotoPose) with its primitive ``manip_<key>``; ``ManipTask`` runs a YAML task file's
skills in order (skillbus.manip.task).
"""

import importlib

from skillbus.manip.primitive import skills_module
from skillbus.manip.task import ManipTask as _ManipTaskDescription, manip_task as _manip_task

for _family in ("articulation", "heuristic", "motion", "pick"):  # importing them registers the skills
    importlib.import_module(f"skillbus.manip.family.{_family}")

globals().update(skills_module(__name__))


class ManipTask(_ManipTaskDescription):
    __doc__ = _ManipTaskDescription.__doc__


class manip_task(_manip_task):
    def createDescription(self):
        self.setDescription(ManipTask(), "manip_task")
