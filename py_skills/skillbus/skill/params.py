"""Skill parameters under SkiROS2's module name (skiros2_common.core.params): ParamTypes,
Param (skillbus.skill.param) and ParamHandler (skillbus.skill.param_handler).

    >>> ph = ParamHandler()
    >>> ph.addParam("Speed", 0.5, ParamTypes.Optional)
    >>> ph.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
    >>> ph.getParamValue("Speed"), ph["Object"].dataTypeIs(Element)
    (0.5, True)
    >>> ph.getParamValue("Nope") is None   # a missing key logs an error, as in SkiROS2
    True
"""

from skillbus.skill.param import Param, ParamTypes
from skillbus.skill.param_handler import ParamHandler
from skillbus.world.element import Element

__all__ = ["Element", "Param", "ParamHandler", "ParamTypes"]  # Element: SkiROS2's module has it too
