"""A library that brings a processor of its own, which the skill manager does not know."""

from skillbus.skill import SerialStar, SkillBase, SkillDescription
from skillbus.skill.processors import Processor


class Fancy(Processor):
    """Not in the manager's registry: the process reports it when it registers."""


class UsesFancy(SkillDescription):
    def createDescription(self):
        pass


class uses_fancy(SkillBase):
    def createDescription(self):
        self.setDescription(UsesFancy(), "uses_fancy")

    def expand(self, skill):
        skill.setProcessor(Fancy())
        skill(self.skill(SerialStar()))
