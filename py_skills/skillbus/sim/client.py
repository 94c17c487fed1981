"""The physics server's control services over RPC (area SIM)."""

from __future__ import annotations

from typing import Any

from skillbus.bus import Bus
from skillbus.msgs import sim_control_t, sim_status_t
from skillbus.rpc import RpcClient


class SimClient:
    def __init__(self, bus: Bus, name: str = "sim-client", timeout: float = 5.0) -> None:
        self.rpc = RpcClient(bus, "SIM", name)
        self.timeout = timeout

    def _call(self, method: str, scene: str = "") -> dict[str, Any]:
        req = sim_control_t()
        req.scene = scene
        rep = self.rpc.call(method, req, sim_status_t, timeout=self.timeout)
        return {k: getattr(rep, k) for k in sim_status_t.__slots__}

    def status(self) -> dict[str, Any]:
        return self._call("status")

    def digest(self) -> str:
        return self._call("digest")["digest"]

    def reset(self) -> dict[str, Any]:
        return self._call("reset")

    def load_scene(self, path: str) -> dict[str, Any]:
        return self._call("load_scene", path)

    def pause(self) -> dict[str, Any]:
        return self._call("pause")

    def resume(self) -> dict[str, Any]:
        return self._call("resume")
