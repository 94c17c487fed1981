"""A test library for task planning (test_task_plan.py): a mobile robot that drives
between shelves (skiros:at), fetches products from the shelf it is at and drops them
there (skiros:contain). The primitives only change the world model, after a few ticks
(time for a test to change the world mid-plan)."""

import time

from skillbus.skill import ConditionRelation, Element, ParamTypes, PrimitiveBase, SkillBase, SkillDescription
from skillbus.world.poses import reparent

TICKS = 5  # each skill takes this many ticks


class Drive(SkillDescription):
    def createDescription(self):
        self.addParam("Mover", Element("skiros:Robot"), ParamTypes.Required)
        self.addParam("From", Element("skiros:Location"), ParamTypes.Required)
        self.addParam("To", Element("skiros:Location"), ParamTypes.Required)
        self.addPreCondition(ConditionRelation("AtStart", "skiros:at", "Mover", "From", True))
        self.addPostCondition(ConditionRelation("LeftStart", "skiros:at", "Mover", "From", False))
        self.addPostCondition(ConditionRelation("Arrived", "skiros:at", "Mover", "To", True))


class Fetch(SkillDescription):
    def createDescription(self):
        self.addParam("Mover", Element("skiros:Robot"), ParamTypes.Required)
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addParam("Shelf", Element("skiros:Location"), ParamTypes.Required)
        self.addPreCondition(ConditionRelation("There", "skiros:at", "Mover", "Shelf", True))
        self.addPreCondition(ConditionRelation("OnShelf", "skiros:contain", "Shelf", "Object", True))
        self.addPostCondition(ConditionRelation("Carried", "skiros:contain", "Mover", "Object", True))


class Drop(SkillDescription):
    def createDescription(self):
        self.addParam("Mover", Element("skiros:Robot"), ParamTypes.Required)
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addParam("Shelf", Element("skiros:Location"), ParamTypes.Required)
        self.addPreCondition(ConditionRelation("There", "skiros:at", "Mover", "Shelf", True))
        self.addPreCondition(ConditionRelation("Carried", "skiros:contain", "Mover", "Object", True))
        self.addPostCondition(ConditionRelation("Dropped", "skiros:contain", "Shelf", "Object", True))


class _Slow(PrimitiveBase):
    def onStart(self):
        self.ticks = 0
        return True

    def execute(self):
        self.ticks += 1
        if self.ticks < TICKS:
            return self.step(f"{self.label}: tick {self.ticks}")
        self.act()
        return self.success(f"{self.label} done")

    def act(self) -> None:
        raise NotImplementedError


class drive(_Slow):
    """Leaves at its first tick (the robot is then at no shelf), arrives at its last."""

    def createDescription(self):
        self.setDescription(Drive(), "drive")

    def execute(self):
        if self.ticks == 0:
            self.wmi.set_relation(self.params["Mover"].value.id, "skiros:at", self.params["From"].value.id, False)
        return super().execute()

    def act(self) -> None:
        self.wmi.set_relation(self.params["Mover"].value.id, "skiros:at", self.params["To"].value.id, True)


class fetch(_Slow):
    def createDescription(self):
        self.setDescription(Fetch(), "fetch")

    def act(self) -> None:
        reparent(self.wmi, self.params["Object"].value.id, self.params["Mover"].value.id)


class drop(_Slow):
    def createDescription(self):
        self.setDescription(Drop(), "drop")

    def act(self) -> None:
        reparent(self.wmi, self.params["Object"].value.id, self.params["Shelf"].value.id)



class Ponder(SkillDescription):
    """A compound whose expansion takes `Seconds` (as a large plan would): longer than the
    manager's 3 s of skill-process liveness and the CLI's 3.5 s of manager silence."""

    def createDescription(self):
        self.addParam("Seconds", 4.5, ParamTypes.Optional)


class ponder(SkillBase):
    available_for_planning = False

    def createDescription(self):
        self.setDescription(Ponder(), "ponder")

    def expand(self, skill):
        time.sleep(float(self.params["Seconds"].value))
