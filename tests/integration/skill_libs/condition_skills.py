"""A test library: one skill per condition class, grounding, a hold-condition, and
primitives that idle (PrimitiveBase.idle_until)."""

from skillbus import tick_context
from skillbus.skill import (ConditionAbstractRelation, ConditionGenerate, ConditionHasProperty, ConditionIsSpecified,
                            ConditionOnType, ConditionProperty, ConditionRelation, Element, InferInvalid, Loop,
                            ParallelFf, ParamTypes, SkillBase,
                            PrimitiveBase, SkillDescription)


def two(self):
    self.addParam("Subject", Element("skiros:PhysicalObject"), ParamTypes.Optional)
    self.addParam("Object", Element("skiros:PhysicalObject"), ParamTypes.Optional)


class CheckHasProperty(SkillDescription):
    def createDescription(self):
        two(self)
        self.addPreCondition(ConditionHasProperty("HasSize", "skiros:Size", "Subject", True))


class CheckProperty(SkillDescription):
    def createDescription(self):
        two(self)
        self.addPreCondition(ConditionProperty("High", "skiros:PositionZ", "Subject", ">", 0.4, True))


class CheckRelation(SkillDescription):
    def createDescription(self):
        two(self)
        self.addPreCondition(ConditionRelation("Contains", "skiros:contain", "Subject", "Object", True))


class CheckAbstractRelation(SkillDescription):
    def createDescription(self):
        two(self)
        self.addPreCondition(ConditionAbstractRelation("MayContain", "skiros:contain", "Subject", "Object", True))


class CheckIsSpecified(SkillDescription):
    def createDescription(self):
        two(self)
        self.addPreCondition(ConditionIsSpecified("Given", "Subject", True))


class CheckGenerate(SkillDescription):
    def createDescription(self):
        two(self)
        self.addPreCondition(ConditionGenerate("Made", "Subject", True))


class CheckOnType(SkillDescription):
    def createDescription(self):
        two(self)
        self.addPreCondition(ConditionOnType("IsProduct", "Subject", "skiros:Product"))


class GroundMe(SkillDescription):
    """Gripper is inferred; Object must be on the table (grounded jointly)."""

    def createDescription(self):
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Inferred)
        self.addParam("Table", Element("skiros:Table"), ParamTypes.Inferred)
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addPreCondition(ConditionRelation("OnTable", "skiros:contain", "Table", "Object", True))


class Hold(SkillDescription):
    def createDescription(self):
        self.addParam("Table", Element("skiros:Table"), ParamTypes.Inferred)
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addHoldCondition(ConditionRelation("StillOnTable", "skiros:contain", "Table", "Object", True))


def _prim(desc):
    class P(PrimitiveBase):
        def createDescription(self):
            self.setDescription(desc(), desc.__name__.lower())

        def execute(self):
            got = ", ".join(f"{k}={p.value.id if isinstance(p.value, Element) else p.value}"
                            for k, p in sorted(self.params.items()) if p.value is not None)
            return self.success(got)
    P.__name__ = desc.__name__.lower()
    P.__qualname__ = P.__name__
    return P


checkhasproperty = _prim(CheckHasProperty)
checkproperty = _prim(CheckProperty)
checkrelation = _prim(CheckRelation)
checkabstractrelation = _prim(CheckAbstractRelation)
checkisspecified = _prim(CheckIsSpecified)
checkgenerate = _prim(CheckGenerate)
checkontype = _prim(CheckOnType)
groundme = _prim(GroundMe)


class hold(PrimitiveBase):
    """Runs for 10,000 ticks (400 s: longer than any test waits) unless its hold-condition
    breaks first."""

    def createDescription(self):
        self.setDescription(Hold(), "hold")

    def onStart(self):
        self.n = 0
        return True

    def execute(self):
        self.n += 1
        return self.step(f"holding {self.n}") if self.n < 10_000 else self.success("held")


class idle_hold(PrimitiveBase):
    """Hold's other implementation: idle (PrimitiveBase.idle_until) for 400 s at every
    execute. The manager must still judge its hold-condition, and stop it, at every tick."""

    def createDescription(self):
        self.setDescription(Hold(), "idle_hold")

    def execute(self):
        self.idle_until(tick_context.now_s() + 400)
        return self.step("idling")


class IdleWait(SkillDescription):
    def createDescription(self):
        self.addParam("Seconds", 1.0, ParamTypes.Optional)


class idle_wait(PrimitiveBase):
    """Waits `Seconds` of the ticks' clock, idle in between; says how often it ran."""

    def createDescription(self):
        self.setDescription(IdleWait(), "idle_wait")

    def onStart(self):
        self.n, self.until = 0, tick_context.now_s() + self.params["Seconds"].value
        return True

    def execute(self):
        self.n += 1
        if tick_context.now_s() >= self.until:
            return self.success(f"waited, executed {self.n} times")
        self.idle_until(self.until)
        return self.step(f"waiting, executed {self.n} times")


class FlagWatch(SkillDescription):
    def createDescription(self):
        self.addParam("Flag", False, ParamTypes.Optional)


class flag_watch(PrimitiveBase):
    """Idle for 400 s unless its Flag is up: a sibling that raises it (the blackboard) must
    get it ticked at once."""

    def createDescription(self):
        self.setDescription(FlagWatch(), "flag_watch")

    def execute(self):
        if self.params["Flag"].value:
            return self.success("saw the flag")
        self.idle_until(tick_context.now_s() + 400)
        return self.step("watching")


class flag_raise(PrimitiveBase):
    """Raises Flag at its third execute."""

    def createDescription(self):
        self.setDescription(FlagWatch(), "flag_raise")

    def onStart(self):
        self.n = 0
        return True

    def execute(self):
        self.n += 1
        if self.n < 3:
            return self.step("not yet")
        self.params["Flag"].value = True
        return self.success("raised")


class WatchFlag(SkillDescription):
    def createDescription(self):
        self.addParam("Flag", False, ParamTypes.Optional)


class watch_flag(SkillBase):
    def createDescription(self):
        self.setDescription(WatchFlag(), "watch_flag")

    def expand(self, skill):
        skill.setProcessor(ParallelFf())
        skill(self.skill("FlagWatch", "flag_watch"), self.skill("FlagWatch", "flag_raise"))


# ---- alternatives and InferInvalid -------------------------------------------------
class PickUp(SkillDescription):
    """Two implementations: one needs a cylinder (none in the demo scene), one a cube."""

    def createDescription(self):
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)


class pickup_cylinder(PrimitiveBase):
    def createDescription(self):
        self.setDescription(PickUp(), "a_pickup_cylinder")  # first in label order
        self.description.addPreCondition(ConditionOnType("IsCylinder", "Object", "skiros:Cylinder"))

    def execute(self):
        return self.success(f"cylinder {self.params['Object'].value.id}")


class pickup_cube(PrimitiveBase):
    def createDescription(self):
        self.setDescription(PickUp(), "b_pickup_cube")
        self.description.addPreCondition(ConditionOnType("IsCube", "Object", "skiros:Cube"))

    def execute(self):
        return self.success(f"cube {self.params['Object'].value.id}")


class Clear(SkillDescription):
    """Moves every cube from the table to the bin, re-inferring Object each round."""

    def createDescription(self):
        self.addParam("Table", Element("skiros:Table"), ParamTypes.Inferred)
        self.addParam("Bin", Element("skiros:Bin"), ParamTypes.Inferred)
        self.addParam("Object", Element("skiros:Cube"), ParamTypes.Optional)
        self.addParam("Moved", list, ParamTypes.Optional)
        self.addPreCondition(ConditionRelation("OnTable", "skiros:contain", "Table", "Object", True))


class MoveToBin(SkillDescription):
    def createDescription(self):
        self.addParam("Table", Element("skiros:Table"), ParamTypes.Required)
        self.addParam("Bin", Element("skiros:Bin"), ParamTypes.Required)
        self.addParam("Object", Element("skiros:Cube"), ParamTypes.Required)
        self.addParam("Moved", list, ParamTypes.Optional)


class move_to_bin(PrimitiveBase):
    def createDescription(self):
        self.setDescription(MoveToBin(), "move_to_bin")

    def execute(self):
        t, b, o = (self.params[k].value.id for k in ("Table", "Bin", "Object"))
        self.wmi.set_relation(t, "skiros:contain", o, False)
        self.wmi.set_relation(b, "skiros:contain", o, True)
        self.params["Moved"].value = (self.params["Moved"].value or []) + [o]
        return self.success(f"moved {o}")


class clear(SkillBase):
    def createDescription(self):
        self.setDescription(Clear(), "clear")

    def expand(self, skill):
        from skillbus.skill import InferInvalid, Loop
        skill.setProcessor(Loop(3))
        skill(self.skill(InferInvalid())(self.skill("MoveToBin", "")))
