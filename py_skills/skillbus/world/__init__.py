"""The world model, from Python: SkiROS2's Element and a world-model interface.

Example::

    wmi = WorldModelInterface(open_bus(), "my_tool")
    cube = wmi.add_element(Element("skiros:Cube", "red"))
    cube.setProperty("skiros:PositionX", 0.3)
    wmi.update_element(cube)
    for e in wmi.resolve_elements(Element("skiros:Product")):
        print(e.id, e.label)
"""

from skillbus.world.element import Element
from skillbus.world.property import Property
from skillbus.world.client import WorldModelError, WorldModelInterface

__all__ = ["Element", "Property", "WorldModelError", "WorldModelInterface"]
