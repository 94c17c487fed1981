"""Asking a depth camera for a capture and receiving its cloud (docs/perception.md).

Requests are camera_capture_t on SB_CAMERA_CAPTURE; clouds come back as camera_cloud_t
parts on SB_CAMERA_CLOUD, carrying the request's id (or none, for a camera's own rate).
Under lockstep the request is a participant's stamped message (published in a frame, or
held to the next frame when made in a skill's tick) and the physics server captures at the
start of the next frame: the cloud is the same on every run. On the wall clock (a physics
server with --wall-clock, or a real camera's driver) `capture()` asks and waits.
"""

from __future__ import annotations

import logging
import os
import secrets
import time
from typing import Any

from skillbus.bus import Bus, channel
from skillbus.log import BadInputCounter
from skillbus.msgs import camera_capture_t, camera_cloud_t, decode, header_t
from skillbus.perception.cloud import Cloud, CloudAssembler, CloudError

log = logging.getLogger("depth camera")


def capture_channel() -> str:
    return channel("SB_CAMERA_CAPTURE")


def cloud_channel() -> str:
    return channel("SB_CAMERA_CLOUD")


class CameraError(RuntimeError):
    pass


class DepthCamera:
    """Collects every cloud on SB_CAMERA_CLOUD (the latest per camera, and those answering
    this client's requests) and sends requests."""

    def __init__(self, bus: Bus, participant: Any = None, name: str = "camera-client", keep: int = 16) -> None:
        self.bus, self.participant, self.name = bus, participant, name
        self.latest: dict[str, Cloud] = {}
        self._answers: dict[str, Cloud | str] = {}  # request id -> cloud, or the refusal
        self._asked: list[str] = []  # our requests not yet answered, oldest first
        self._keep = keep
        self._assembler = CloudAssembler()
        self._count = 0
        # Request ids: under lockstep the participant's name and a count (they are in the
        # session's messages: the same every run); otherwise also this process's pid and a
        # nonce, so two clients, or a client and its predecessor (a transport that keeps
        # messages for late joiners, as DDS does), never take each other's answers.
        self._id_prefix = name if participant is not None else f"{name}:{os.getpid()}:{secrets.token_hex(4)}"
        self.bad_input = BadInputCounter(f"depth camera {name}")
        if participant is not None:
            participant.subscribe(cloud_channel(), lambda m: self._on_part(m.data, m.stamp.frame))
        else:
            bus.subscribe(cloud_channel(), lambda ch, d: self._on_part(d, -1))

    def request(self, camera: str) -> str:
        """Asks `camera` for a capture; returns the request's id (under lockstep this
        client's name and a count: the same every run)."""
        if not camera:
            raise CameraError("a capture request needs a camera name")
        m = camera_capture_t()
        self._count += 1
        m.id, m.camera = f"{self._id_prefix}-{self._count}", camera
        if self.participant is not None:
            self.participant.publish(capture_channel(), m)
        else:
            h = header_t()
            h.frame, h.sim_time_ns, h.sender, h.seq = -1, 0, self.name, self._count
            m.header = h
            self.bus.publish(capture_channel(), m.encode())
        self._asked.append(m.id)
        return m.id

    def answer(self, request_id: str) -> Cloud | None:
        """The cloud answering a request once it is complete (None before); raises
        CameraError with the server's reason if the request was refused."""
        a = self._answers.get(request_id)
        if isinstance(a, str):
            raise CameraError(a)
        return a

    def capture(self, camera: str, timeout: float = 5.0) -> Cloud:
        """Wall clock only: asks and waits for the whole cloud."""
        if self.participant is not None:
            raise CameraError("capture() waits on the wall clock; under lockstep request() in one frame and read "
                              "answer() in a later one")
        rid = self.request(camera)
        deadline = time.monotonic() + timeout
        while (cloud := self.answer(rid)) is None:
            left = deadline - time.monotonic()
            if left <= 0:
                raise CameraError(f"no cloud from camera '{camera}' within {timeout:.1f} s (is a physics server with "
                                  f"that camera running in wall-clock mode? Under lockstep only a participant's "
                                  f"request is heard: wait for the camera's rate with --next)")
            self.bus.handle(min(left, 0.05))
        return cloud

    def next_cloud(self, camera: str, timeout: float = 5.0) -> Cloud:
        """Wall clock: the next complete cloud of `camera`, whoever asked for it."""
        seen = self.latest.get(camera)
        deadline = time.monotonic() + timeout
        while (c := self.latest.get(camera)) is seen:
            left = deadline - time.monotonic()
            if left <= 0:
                raise CameraError(f"no cloud from camera '{camera}' within {timeout:.1f} s")
            self.bus.handle(min(left, 0.05))
        return c

    def _on_part(self, data: bytes, frame: int) -> None:
        m = decode(camera_cloud_t, data)
        if m is None:
            self.bad_input.record(cloud_channel(), "not a camera_cloud_t", len(data))
            return
        if m.error:
            self._answer(m.request_id, m.error)
            return
        try:
            cloud = self._assembler.add(m, frame)
        except CloudError as e:
            self.bad_input.record(cloud_channel(), str(e), len(data))
            return
        if cloud is None:
            return
        self.latest[cloud.camera] = cloud
        self._answer(cloud.request_id, cloud)

    def _answer(self, request_id: str, a: Cloud | str) -> None:
        if request_id not in self._asked:
            return  # another client's, or a capture at a camera's rate
        self._asked.remove(request_id)
        self._answers[request_id] = a
        while len(self._answers) > self._keep:  # (answers nobody collected)
            del self._answers[next(iter(self._answers))]


class DepthCameraInterface:
    """A skill process's depth camera (``--interface depth_camera=skillbus.perception.
    depth_camera:CAMERA[:NOISE_M]``): the camera Locate asks, and the range noise its
    segmentation allows for (the camera's noise_stddev_m; 0 by default)."""

    def __init__(self, camera: DepthCamera, name: str, noise_m: float = 0.0) -> None:
        self.camera, self.name, self.noise_m = camera, name, noise_m


def interface(bus: Bus, participant: Any = None, arg: str = "", **options: Any) -> DepthCameraInterface:
    """The depth camera interface (skillbus.robot.interfaces): `arg` is CAMERA[:NOISE_M]."""
    name, _, noise = arg.partition(":")
    if not name:
        raise CameraError("the depth camera interface needs the camera's name: "
                          "depth_camera=skillbus.perception.depth_camera:CAMERA[:NOISE_M]")
    try:
        noise_m = float(noise) if noise else 0.0
    except ValueError:
        raise CameraError(f"depth camera {name}: the noise must be a number of metres, not {noise!r}") from None
    if not noise_m >= 0:
        raise CameraError(f"depth camera {name}: the noise must be >= 0 m")
    # Request ids name the process (under lockstep they are in the session's messages).
    client = participant.name if participant is not None else "camera-client"
    return DepthCameraInterface(DepthCamera(bus, participant, name=client), name, noise_m)


def depth_camera() -> DepthCameraInterface | None:
    """The process's depth camera interface, or None when it has none."""
    from skillbus.robot import interfaces
    try:
        return interfaces.get("depth_camera", hint="--interface depth_camera=skillbus.perception.depth_camera:CAMERA")
    except interfaces.InterfaceError:
        return None
