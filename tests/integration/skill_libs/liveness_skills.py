"""A compound whose child (Echo) lives in another skill process (safety_skills)."""

from skillbus.skill import SkillBase, SkillDescription


class UsesEcho(SkillDescription):
    def createDescription(self):
        pass


class uses_echo(SkillBase):
    def createDescription(self):
        self.setDescription(UsesEcho(), "uses_echo")

    def expand(self, skill):
        skill(self.skill("Echo", ""))
