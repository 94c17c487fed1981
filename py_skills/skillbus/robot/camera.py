"""The camera of a skill process (``skills-process --interface camera=skillbus.robot.camera``):
what the robot's camera sees, as its driver publishes it (robot_objects_t on
SB_ROBOT_OBJECTS): every object detected, with its name and world pose. The physics
server publishes a perfect camera (every object of the scene, exact poses); a real
camera's driver publishes its detections. `Locate` reads it.

Under lockstep the detections are a lockstep subscription (a tick of frame n sees those
of frame n); on the wall clock they come straight over the bus. The latest message is
decoded only when a skill asks.
"""

from __future__ import annotations

from typing import Any

from skillbus.bus import Bus
from skillbus.msgs import robot_object_t, robot_objects_t
from skillbus.robot.latest import LatestReading
from skillbus.robot.messages import check_objects, objects_channel


class CameraError(RuntimeError):
    pass


class Camera(LatestReading[robot_objects_t]):
    def __init__(self, bus: Bus, participant: Any = None) -> None:
        # (checked before Locate writes a pose into the world; the last good view stays)
        super().__init__(bus, participant, objects_channel(), robot_objects_t, check_objects, "camera")

    def objects(self) -> list[robot_object_t]:
        """Every object in the latest detections (name, pose: x y z qx qy qz qw, world)."""
        m = self.latest
        if m is None:
            raise CameraError(f"no detections yet on {objects_channel()} (is the physics server or the camera's "
                              "driver running?)")
        return list(m.objects)


def interface(bus: Bus, participant: Any = None, arg: str = "", **options: Any) -> Camera:
    """The camera interface (skillbus.robot.interfaces): the detections on the robot's
    channel. `arg` is unused."""
    return Camera(bus, participant)


def camera() -> Camera:
    """The process's camera interface."""
    from skillbus.robot import interfaces
    try:
        return interfaces.get("camera", hint="--interface camera=skillbus.robot.camera")
    except interfaces.InterfaceError as e:
        raise CameraError(str(e)) from None
