"""The 3D view's frames, live (from the bus) and in replay (from a log): the moving
bodies' poses, the finger contacts and the tool's path along the arm's latest
trajectory command, computed with skillbus.console.scene3d."""

from __future__ import annotations

from typing import Any, Callable

from skillbus.channels import robot_channel
from skillbus.console.scene3d import Scene3D, sim_state_view
from skillbus.msgs import decode, robot_arm_cmd_t, sim_state_t

SEND_PERIOD_S = 0.1   # live: at most this often to browsers, however fast the lockstep runs


def frame_view(scene: Scene3D, state, arm_cmd, frame: int) -> dict[str, Any]:
    joints, objects, contacts = sim_state_view(state)
    path = []
    if arm_cmd is not None and arm_cmd.points:
        path = scene.tool_path(list(arm_cmd.joint_names), [list(p.positions) for p in arm_cmd.points])
    return {"frame": frame, "sim_time_s": state.header.sim_time_ns * 1e-9, "poses": scene.poses(joints, objects),
            "contacts": contacts, "path": path, "finger_width_mm": round(state.finger_width * 1000, 1),
            "held": sorted({c["b"] for c in contacts})}


class LiveSim:
    """Hears the robot's physics state and arm commands; a chore sends the latest frame."""

    def __init__(self, bus, scene: Scene3D, emit: Callable[[dict[str, Any]], None], robot: str = "") -> None:
        self.scene, self.emit = scene, emit
        self.state: Any = None
        self._raw: bytes | None = None
        self.arm_cmd: Any = None
        self._sent = None
        bus.subscribe(robot_channel("SB_SIM_STATE", robot), self._on_state)
        bus.subscribe(robot_channel("SB_ROBOT_ARM_CMD", robot), self._on_cmd)

    def _on_state(self, ch: str, data: bytes) -> None:
        self._raw = data  # decoded when sent: at most every SEND_PERIOD_S, not every frame

    def _decoded(self) -> None:
        raw, self._raw = self._raw, None
        if raw is not None:
            s = decode(sim_state_t, raw)
            if s is not None:
                self.state = s

    def _on_cmd(self, ch: str, data: bytes) -> None:
        c = decode(robot_arm_cmd_t, data)
        if c is not None:
            self.arm_cmd = c

    def latest(self) -> dict[str, Any] | None:
        self._decoded()
        if self.state is None:
            return None
        return frame_view(self.scene, self.state, self.arm_cmd, self.state.header.frame)

    def send(self) -> None:
        """Chore: the latest frame to browsers, when there is a new one."""
        self._decoded()
        if self.state is None or self._sent is self.state:
            return
        self._sent = self.state
        self.emit(dict(self.latest(), kind="sim"))
