"""A test library with one broken skill among good ones: the good ones must still load."""

from skillbus.skill import ParamTypes, PrimitiveBase, SkillDescription


class Fine(SkillDescription):
    def createDescription(self):
        self.addParam("X", 1, ParamTypes.Optional)


class Broken(SkillDescription):
    def createDescription(self):
        self.addPreCondition(self.getIsSpecifiedCond("Needs", "Missing"))  # no such parameter


class fine(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Fine(), self.__class__.__name__)


class broken(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Broken(), self.__class__.__name__)
