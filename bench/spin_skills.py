"""A primitive that is always running (the tick round-trip benchmark's peer)."""

from skillbus.skill import PrimitiveBase, SkillDescription


class Spin(SkillDescription):
    pass


class spin(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Spin(), "spin")

    def execute(self):
        return self.step("spinning")
