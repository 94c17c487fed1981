"""The 3D view's frames, live (from the bus) and in replay (from a log): the moving
bodies' poses, the finger contacts and the tool's path along the arm's latest
trajectory command, computed with skillbus.console.scene3d."""

from __future__ import annotations

import time
from typing import Any, Callable

from skillbus.channels import robot_channel
from skillbus.console.scene3d import Scene3D, sim_state_view
from skillbus.msgs import decode, robot_arm_cmd_t, sim_state_t

SEND_PERIOD_S = 0.1   # live: at most this often to browsers, however fast the lockstep runs
ASKED_GRACE_S = 10.0  # after GET /api/sim the state is heard this long, a page open or not


def frame_view(scene: Scene3D, state, arm_cmd, frame: int) -> dict[str, Any]:
    joints, objects, contacts = sim_state_view(state)
    path = []
    if arm_cmd is not None and arm_cmd.points:
        path = scene.tool_path(list(arm_cmd.joint_names), [list(p.positions) for p in arm_cmd.points])
    return {"frame": frame, "sim_time_s": state.header.sim_time_ns * 1e-9, "poses": scene.poses(joints, objects),
            "contacts": contacts, "path": path, "finger_width_mm": round(state.finger_width * 1000, 1),
            "held": sorted({c["b"] for c in contacts})}


class LiveSim:
    """The robot's physics state and arm commands, for the 3D view. The state comes every
    frame: it is heard only while a page is open (send(watched)), and decoded at most
    every SEND_PERIOD_S."""

    def __init__(self, bus, scene: Scene3D, emit: Callable[[dict[str, Any]], None], robot: str = "") -> None:
        self.bus, self.scene, self.emit, self.robot = bus, scene, emit, robot
        self.state: Any = None
        self._state_at = 0.0  # when the state shown arrived (monotonic)
        self._asked_at = -ASKED_GRACE_S  # when GET /api/sim last asked (heard that long after, page or not)
        self._raw: bytes | None = None
        self._raw_at = 0.0
        self._state_sub: int | None = None
        self.arm_cmd: Any = None
        self._path: tuple[Any, list] = (None, [])  # (the command, its tool path): computed once per command
        self._sent = None
        self.refused = 0  # physics states that could not be drawn (not finite)
        bus.subscribe(robot_channel("SB_ROBOT_ARM_CMD", robot), self._on_cmd)

    def hear(self, on: bool) -> None:
        if on and self._state_sub is None:
            self._state_sub = self.bus.subscribe(robot_channel("SB_SIM_STATE", self.robot), self._on_state)
        elif not on and self._state_sub is not None:
            self.bus.unsubscribe(self._state_sub)
            self._state_sub = None

    def _on_state(self, ch: str, data: bytes) -> None:
        self._raw = data  # decoded when sent: at most every SEND_PERIOD_S, not every frame
        self._raw_at = time.monotonic()

    def _on_cmd(self, ch: str, data: bytes) -> None:
        c = decode(robot_arm_cmd_t, data)
        if c is not None:
            self.arm_cmd = c

    def _decoded(self) -> None:
        raw, self._raw = self._raw, None
        if raw is not None:
            s = decode(sim_state_t, raw)
            if s is not None:
                try:
                    sim_state_view(s)
                except ValueError:
                    self.refused += 1  # (kept: the last state that can be drawn)
                    return
                self.state, self._state_at = s, self._raw_at

    def latest(self) -> dict[str, Any] | None:
        """The latest state heard, drawn, with its age (`age_s`): a script that asks while
        no page is open gets the state heard since its last call (within ASKED_GRACE_S the
        console goes on hearing it), and can tell an old one."""
        self._asked_at = time.monotonic()
        self.hear(True)
        self._decoded()
        if self.state is None:
            return None
        if self._path[0] is not self.arm_cmd:
            self._path = (self.arm_cmd, frame_view(self.scene, self.state, self.arm_cmd, 0)["path"])
        view = frame_view(self.scene, self.state, None, self.state.header.frame)
        view["path"] = self._path[1]
        view["age_s"] = round(time.monotonic() - self._state_at, 3)
        return view

    def send(self, watched: bool) -> None:
        """Chore: the latest frame to browsers, when there is a new one and a page open."""
        # (heard also for a while after GET /api/sim: a script polling it, no page open,
        # was unsubscribed between its calls and got a 404 or the state of its last call)
        self.hear(watched or time.monotonic() - self._asked_at < ASKED_GRACE_S)
        if not watched:
            return
        self._decoded()
        if self.state is None or self._sent is self.state:
            return
        self._sent = self.state
        self.emit(dict(self.latest(), kind="sim"))
