"""Test library of process A: Count, and the compound Both, whose children live in two processes."""

from skillbus.skill import ParamTypes, PrimitiveBase, SerialStar, SkillBase, SkillDescription


class Count(SkillDescription):
    def createDescription(self):
        self.addParam("N", 20, ParamTypes.Optional)
        self.addParam("Total", 0, ParamTypes.Optional)


class Both(SkillDescription):
    def createDescription(self):
        self.addParam("Total", 0, ParamTypes.Optional)


class count(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Count(), "count")

    def onStart(self):
        self.n = 0
        return True

    def execute(self):
        self.n += 1
        self.params["Total"].value = self.params["Total"].value + 1
        return self.step(f"{self.n}") if self.n < self.params["N"].value else self.success(f"counted {self.n}")


class both(SkillBase):
    def createDescription(self):
        self.setDescription(Both(), "both")

    def expand(self, skill):
        skill.setProcessor(SerialStar())
        skill(self.skill("Count", ""), self.skill("Other", ""), self.skill("Count", "", specify={"N": 5}))
