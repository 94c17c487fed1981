"""Skills for the safety tests (test_safe_execution.py): each one makes a wrong value,
a lost write or a skipped check visible in its result or in its process's log."""

import sys

from skillbus.skill import (ConditionRelation, Element, ParamTypes, PrimitiveBase, SerialStar, SkillBase,
                            SkillDescription)


class Inspect(SkillDescription):
    def createDescription(self):
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)


class inspect_(PrimitiveBase):
    """Reports the object's id, label and height: a property the manager's copy must carry."""

    def createDescription(self):
        self.setDescription(Inspect(), "inspect")

    def execute(self):
        o = self.params["Object"].value
        return self.success(f"{o.id} is {o.label} at z={o.getProperty('skiros:PositionZ').value}")


class Echo(SkillDescription):
    def createDescription(self):
        self.addParam("N", 1, ParamTypes.Required)          # static unless the user gives it
        self.addParam("Flag", False, ParamTypes.Optional)


class echo(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Echo(), "echo")

    def execute(self):
        return self.success(f"N={self.params['N'].value} Flag={self.params['Flag'].value}")


class Fill(SkillDescription):
    def createDescription(self):
        self.addParam("Queue", str, ParamTypes.Optional)


class fill(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Fill(), "fill")

    def execute(self):
        self.params["Queue"].values = ["a", "b", "c"]
        return self.success("filled")


class Drain(SkillDescription):
    def createDescription(self):
        self.addParam("Queue", str, ParamTypes.Optional)
        self.addParam("Ticks", 0, ParamTypes.Optional)


class drain(PrimitiveBase):
    """Consumes one item a tick; done when the queue is empty (gives up after 20 ticks)."""

    def createDescription(self):
        self.setDescription(Drain(), "drain")

    def onStart(self):
        self.n = 0
        return True

    def execute(self):
        self.n += 1
        q = self.params["Queue"]
        if not q.values:
            return self.success(f"drained in {self.n} ticks")
        if self.n > 20:
            return self.fail(f"still {q.values} after {self.n} ticks", -1)
        q.values = q.values[1:]
        return self.step(f"left: {q.values}")


class FillAndDrain(SkillDescription):
    def createDescription(self):
        self.addParam("Queue", str, ParamTypes.Optional)


class fill_and_drain(SkillBase):
    def createDescription(self):
        self.setDescription(FillAndDrain(), "fill_and_drain")

    def expand(self, skill):
        skill.setProcessor(SerialStar())
        skill(self.skill("Fill", ""), self.skill("Drain", ""))


class BadRemap(SkillDescription):
    def createDescription(self):
        pass


class bad_remap(SkillBase):
    def createDescription(self):
        self.setDescription(BadRemap(), "bad_remap")

    def expand(self, skill):
        skill(self.skill("Echo", "", remap={"Inn": "Out"}))


class BadSpecify(SkillDescription):
    def createDescription(self):
        pass


class bad_specify(SkillBase):
    def createDescription(self):
        self.setDescription(BadSpecify(), "bad_specify")

    def expand(self, skill):
        skill(self.skill("Echo", "", specify={"NN": 5}))


class HoldOnTable(SkillDescription):
    def createDescription(self):
        self.addParam("Table", Element("skiros:Table"), ParamTypes.Inferred)
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addHoldCondition(ConditionRelation("OnTable", "skiros:contain", "Table", "Object", True))


class hold_on_table(PrimitiveBase):
    def createDescription(self):
        self.setDescription(HoldOnTable(), "hold_on_table")

    def execute(self):
        print(f"EXECUTED hold_on_table with {self.params['Object'].value.id}", file=sys.stderr, flush=True)
        return self.step("holding")


class Relabel(SkillDescription):
    def createDescription(self):
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)


class relabel(PrimitiveBase):
    """Updates the element it got as a parameter: only the label changes."""

    def createDescription(self):
        self.setDescription(Relabel(), "relabel")

    def execute(self):
        o = self.params["Object"].value
        o.label = o.label + "-seen"
        self.wmi.update_element(o)
        return self.success(f"relabelled {o.id}")


class Greet(SkillDescription):
    def createDescription(self):
        pass


class greet(PrimitiveBase):
    """Relies on onInit, as SkiROS2 skills do (set up once, used in every run)."""

    def createDescription(self):
        self.setDescription(Greet(), "greet")

    def onInit(self):
        self.greeting = "ready"
        return True

    def execute(self):
        return self.success(f"greeting {self.greeting}")


class Count(SkillDescription):
    def createDescription(self):
        self.addParam("Items", list, ParamTypes.Required)


class count(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Count(), "count")

    def execute(self):
        items = self.params["Items"].value
        return self.success(f"{len(items)} items: {items}")


class CountTwo(SkillDescription):
    def createDescription(self):
        pass


class count_two(SkillBase):
    def createDescription(self):
        self.setDescription(CountTwo(), "count_two")

    def expand(self, skill):
        skill(self.skill("Count", "", specify={"Items": ["a", "b"]}))


class BadSpecifyType(SkillDescription):
    def createDescription(self):
        pass


class bad_specify_type(SkillBase):
    def createDescription(self):
        self.setDescription(BadSpecifyType(), "bad_specify_type")

    def expand(self, skill):
        skill(self.skill("Echo", "", specify={"N": "five"}))
