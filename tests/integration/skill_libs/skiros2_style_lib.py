"""A skill library written as a SkiROS2 user writes one, with only its import lines
changed (from skiros2_skill.core.skill / skiros2_common.core.* to skillbus.skill):

- pose_writer moves its Object with Element.setData(":Position"/":Orientation") and
  leaves it in its parameter; pose_reader, the next skill of the tree, reads the pose
  with getData from its own parameter (the change reaches it through the world model);
- watch_forever never ends: under ParallelFs it is stopped when its sibling ends;
- arrange nests anonymous processors: SerialStar( SerialStar(writer, reader),
  ParallelFs(watch_forever, Sequential(work, work)) );
- guarded_read gives a node a pre-condition of its own (self.skill(..., preconditions=[...]))
  named, as SkiROS2 code does, by the remapped key; with Strict it asks for a cylinder.
Used by test_skiros2_style.py."""

from skillbus.skill import ParallelFs, ParamTypes, PrimitiveBase, Sequential, SerialStar, SkillBase, SkillDescription
from skillbus.skill import ConditionOnType, Element

TARGET = (0.25, -0.1, 0.6)


class PoseWriter(SkillDescription):
    def createDescription(self):
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)


class PoseReader(SkillDescription):
    def createDescription(self):
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)


class WatchForever(SkillDescription):
    def createDescription(self):
        pass


class Work(SkillDescription):
    def createDescription(self):
        self.addParam("Ticks", 3, ParamTypes.Optional)


class Arrange(SkillDescription):
    def createDescription(self):
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)


class GuardedRead(SkillDescription):
    def createDescription(self):
        self.addParam("Target", Element("skiros:Product"), ParamTypes.Required)
        self.addParam("Strict", False, ParamTypes.Optional)


class pose_writer(PrimitiveBase):
    def createDescription(self):
        self.setDescription(PoseWriter(), self.__class__.__name__)

    def execute(self):
        obj = self.params["Object"].value
        obj.setData(":Position", TARGET)
        obj.setData(":Orientation", (0.0, 0.0, 0.0, 1.0))
        self.params["Object"].value = obj
        return self.success("moved to {}".format(obj.getData(":Position")))


class pose_reader(PrimitiveBase):
    def createDescription(self):
        self.setDescription(PoseReader(), self.__class__.__name__)

    def execute(self):
        obj = self.params["Object"].value
        if not obj.hasData(":Position"):
            return self.fail("no position", -1)
        position = tuple(round(v, 6) for v in obj.getData(":Position"))
        if position != TARGET:
            return self.fail("at {}, not at {}".format(position, TARGET), -2)
        return self.success("found at {}".format(position))


class watch_forever(PrimitiveBase):
    def createDescription(self):
        self.setDescription(WatchForever(), self.__class__.__name__)

    def execute(self):
        return self.step("watching")


class work(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Work(), self.__class__.__name__)

    def onStart(self):
        self.done = 0
        return True

    def execute(self):
        self.done += 1
        if self.done < self.params["Ticks"].value:
            return self.step("working")
        return self.success("worked {} ticks".format(self.done))


class arrange(SkillBase):
    def createDescription(self):
        self.setDescription(Arrange(), self.__class__.__name__)

    def expand(self, skill):
        skill.setProcessor(SerialStar())
        skill(
            self.skill(SerialStar())(
                self.skill("PoseWriter", ""),
                self.skill("PoseReader", ""),
            ),
            self.skill(ParallelFs())(
                self.skill("WatchForever", ""),
                self.skill(Sequential())(
                    self.skill("Work", ""),
                    self.skill("Work", ""),
                ),
            ),
        )


class guarded_read(SkillBase):
    def createDescription(self):
        self.setDescription(GuardedRead(), self.__class__.__name__)

    def expand(self, skill):
        wanted = "skiros:Cylinder" if self.params["Strict"].value else "skiros:Cube"
        skill(
            self.skill("PoseReader", "", remap={"Object": "Target"},
                       preconditions=[ConditionOnType("TargetIsA", "Target", wanted)]),
        )
