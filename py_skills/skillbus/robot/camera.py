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
from skillbus.msgs import decode, robot_object_t, robot_objects_t
from skillbus.robot.messages import check_objects, objects_channel
from skillbus.validate import BadValue, Rejects


class CameraError(RuntimeError):
    pass


class Camera:
    def __init__(self, bus: Bus, participant: Any = None) -> None:
        self._seen: robot_objects_t | None = None
        self._raw: bytes | None = None
        self.bad = 0  # messages not used: not decodable, or values not sane (by kind: rejects)
        self.rejects = Rejects("camera")
        if participant is not None:
            participant.subscribe(objects_channel(), lambda m: self._on_objects(m.data))
        else:
            bus.subscribe(objects_channel(), lambda ch, d: self._on_objects(d))

    def _on_objects(self, data: bytes) -> None:
        self._raw = data

    @property
    def latest(self) -> robot_objects_t | None:
        """The latest detections, or None before the first."""
        if self._raw is not None:
            m = decode(robot_objects_t, self._raw)
            self._raw = None
            if m is None:
                self.bad += 1
                return self._seen
            try:
                check_objects(m)  # before Locate writes a pose into the world (the last good view stays)
            except BadValue as e:
                self.bad += 1
                self.rejects.record(objects_channel(), e)
                return self._seen
            self._seen = m
        return self._seen

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
