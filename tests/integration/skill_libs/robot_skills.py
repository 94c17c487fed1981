"""A test library: a skill that says which robot it runs for (used by test_several_robots.py)."""

from skillbus.skill import PrimitiveBase, SkillDescription


class WhoAmI(SkillDescription):
    def createDescription(self):
        pass  # (Robot is added to every description; the manager sets it to its own agent)


class who_am_i(PrimitiveBase):
    def createDescription(self):
        self.setDescription(WhoAmI(), self.__class__.__name__)

    def execute(self):
        return self.success(f"I am {self.params['Robot'].value.id}")
