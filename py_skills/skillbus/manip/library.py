"""The manipulation-command skill family as a skill library of the skill process::

    skillbus skills-process --name skills --library skillbus.manip.library --arm --gripper ... \\
        --interface articulation=skillbus.robot.articulation --interface attach=skillbus.sim.attach

Every registered manipulation skill (the family's, and any another module registered
before this one is imported) becomes ``Manip<Name>`` (e.g. ManipPick, ManipOpen,
ManipGotoPose) with its primitive ``manip_<key>``.
"""

from skillbus.manip.family import articulation, heuristic, motion, pick  # noqa: F401 (they register the skills)
from skillbus.manip.primitive import skills_module

globals().update(skills_module(__name__))
