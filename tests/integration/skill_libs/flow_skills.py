"""A test library: skills that pass parameters along (used by test_skills.py)."""

from skillbus.skill import (Element, ParamTypes, PrimitiveBase, Selector, SerialStar, SkillBase, SkillDescription)


class Produce(SkillDescription):
    def createDescription(self):
        self.addParam("Object", str, ParamTypes.Optional)          # an output
        self.addParam("Ticks", 2, ParamTypes.Optional)             # a default


class Consume(SkillDescription):
    def createDescription(self):
        self.addParam("Item", str, ParamTypes.Required)
        self.addParam("Log", list, ParamTypes.Optional)


class Mode(SkillDescription):
    def createDescription(self):
        self.addParam("Mode", "open", ParamTypes.Required)         # static
        self.addParam("Log", list, ParamTypes.Optional)


class Chain(SkillDescription):
    def createDescription(self):
        self.addParam("Object", str, ParamTypes.Optional)
        self.addParam("Log", list, ParamTypes.Optional)


class Fails(SkillDescription):
    def createDescription(self):
        pass


class produce(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Produce(), self.__class__.__name__)

    def onStart(self):
        self.n = 0
        return True

    def execute(self):
        self.n += 1
        if self.n < self.params["Ticks"].value:
            return self.step(f"tick {self.n}")
        self.params["Object"].value = "widget-7"
        return self.success("made widget-7")


class consume(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Consume(), self.__class__.__name__)

    def execute(self):
        log = self.params["Log"].value or []
        log.append(self.params["Item"].value)
        self.params["Log"].value = log
        return self.success(f"consumed {self.params['Item'].value}")


class mode(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Mode(), self.__class__.__name__)

    def execute(self):
        log = self.params["Log"].value or []
        log.append("mode=" + self.params["Mode"].value)
        self.params["Log"].value = log
        return self.success(self.params["Mode"].value)


class fails(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Fails(), self.__class__.__name__)

    def execute(self):
        return self.fail("always fails", -3)


class chain(SkillBase):
    """Produce writes Object; Consume reads it through a remap; the next Consume gets a
    specified value; Mode is static; a Selector falls back past a failure."""

    def createDescription(self):
        self.setDescription(Chain(), self.__class__.__name__)

    def expand(self, skill):
        skill.setProcessor(SerialStar())
        skill(
            self.skill("Produce", ""),
            self.skill("Consume", "", remap={"Item": "Object"}),
            self.skill("Consume", "", specify={"Item": "fixed"}),
            self.skill("Mode", ""),
            self.skill(Selector())(
                self.skill("Fails", ""),
                self.skill("Consume", "", remap={"Item": "Object"}),
            ),
        )


class Wait(SkillDescription):
    def createDescription(self):
        self.addParam("Ticks", 1000, ParamTypes.Optional)


class wait(PrimitiveBase):
    """Counts ticks in its message, for pause, step, resume and stop."""

    def createDescription(self):
        self.setDescription(Wait(), "wait")

    def onStart(self):
        self.n = 0
        return True

    def execute(self):
        self.n += 1
        return self.step(f"tick {self.n}") if self.n < self.params["Ticks"].value else self.success("waited")

    def onPreempt(self):
        return self.fail(f"preempted at tick {self.n}", -1)
