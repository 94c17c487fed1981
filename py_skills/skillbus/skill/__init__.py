"""Everything the skill model names, in one import (SkiROS2's API; port a SkiROS2 skill
library by changing its imports to ``from skillbus.skill import ...``).

Descriptions:  SkillDescription, ParamTypes, ParamOptions, Param, ParamHandler, Element,
               the Condition* classes
Primitives:    PrimitiveBase (step / success / fail), State
Compounds:     SkillBase (expand, self.skill), the processors
"""

from skillbus.skill.conditions import (AbstractConditionRelation, ConditionAbstractRelation, ConditionBase,
                                       ConditionGenerate, ConditionHasProperty, ConditionIsSpecified, ConditionOnType,
                                       ConditionOr, ConditionProperty, ConditionRelation)
from skillbus.skill.description import ParamOptions, SkillDescription
from skillbus.skill.params import Param, ParamHandler, ParamTypes
from skillbus.skill.processors import (InferInvalid, Invert, Loop, NoFail, ParallelFf, ParallelFs, Processor,
                                       RetryOnFail, Selector, SelectorStar, Sequential, Serial, SerialStar)
from skillbus.skill.skill import PrimitiveBase, SkillBase, SkillCore, State
from skillbus.skill.wrapper import SkillWrapper
from skillbus.world.element import Element

__all__ = [
    "AbstractConditionRelation", "ConditionAbstractRelation", "ConditionBase", "ConditionGenerate",
    "ConditionHasProperty", "ConditionIsSpecified", "ConditionOnType", "ConditionOr", "ConditionProperty",
    "ConditionRelation", "Element", "InferInvalid", "Invert", "Loop", "NoFail", "ParallelFf", "ParallelFs", "Param",
    "ParamHandler", "ParamOptions", "ParamTypes", "PrimitiveBase", "Processor", "RetryOnFail", "Selector",
    "SelectorStar", "Sequential", "Serial", "SerialStar", "SkillBase", "SkillCore", "SkillDescription",
    "SkillWrapper", "State",
]
