"""Gripper skills: GripperOpen, GripperClose, Grasp and Release, all served by one primitive,
`GripperPrimitive`, configured by the static parameter Command (a Required parameter
with a value in the description, as SkiROS2 does it).

The primitive drives the CANopen gripper of its skill process (``skills-process
--gripper gripper0:5``) through the non-blocking driver: it sends one set-point and
then only reads the latest status on each tick (and, while the fingers open, is not
ticked before they could be open: GripperPrimitive._idle_while_travelling). Grasp succeeds only when the device
reports an object gripped; it then writes into the world model that the gripper
contains the object (and its old container no longer does), and finishes once its own
replica shows it, so the manager's post-condition sees it too. Release opens and writes
that the location contains the object.
"""

from __future__ import annotations

from skillbus.skill import ConditionRelation, Element, ParamTypes, SkillDescription
from skillbus.skills.gripper_primitive import GripperPrimitive


class GripperOpen(SkillDescription):
    def createDescription(self):
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Required)
        self.addParam("Command", "open", ParamTypes.Required)  # static


class GripperClose(SkillDescription):
    def createDescription(self):
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Required)
        self.addParam("Command", "close", ParamTypes.Required)  # static


class Grasp(SkillDescription):
    def createDescription(self):
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Required)
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addParam("Command", "grasp", ParamTypes.Required)  # static
        self.addPreCondition(ConditionRelation("NotHolding", "skiros:contain", "Gripper", "Object", False))
        self.addPostCondition(ConditionRelation("Holding", "skiros:contain", "Gripper", "Object", True))


class Release(SkillDescription):
    def createDescription(self):
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Required)
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addParam("Location", Element("skiros:Location"), ParamTypes.Required)
        self.addParam("Command", "release", ParamTypes.Required)  # static
        self.addPreCondition(ConditionRelation("Holding", "skiros:contain", "Gripper", "Object", True))
        self.addPostCondition(ConditionRelation("Contains", "skiros:contain", "Location", "Object", True))


class gripper_open(GripperPrimitive):
    def createDescription(self):
        self.setDescription(GripperOpen(), "gripper_open")


class gripper_close(GripperPrimitive):
    def createDescription(self):
        self.setDescription(GripperClose(), "gripper_close")


class grasp(GripperPrimitive):
    # Pick's conditions without Pick's motion: the task planner plans with Pick.
    available_for_planning = False

    def createDescription(self):
        self.setDescription(Grasp(), "grasp")


class release(GripperPrimitive):
    # Place's conditions without Place's motion: the task planner plans with Place.
    available_for_planning = False

    def createDescription(self):
        self.setDescription(Release(), "release")
