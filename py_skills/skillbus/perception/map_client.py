"""The occupancy map's client (map_server, RPC area MAP; docs/perception.md).

Under lockstep a query carries the asker's frame (a skill's tick, or the participant's
frame) and the map server answers it once it has finished that frame: the answer is the
same on every run. Without a participant the map answers as it is.
"""

from __future__ import annotations

from typing import Any, Iterable, Sequence

from skillbus import tick_context as context
from skillbus.bus import Bus
from skillbus.msgs import map_query_t, map_reply_t
from skillbus.rpc import RpcClient

STATES = {map_reply_t.FREE: "free", map_reply_t.OCCUPIED: "occupied", map_reply_t.UNKNOWN: "unknown"}


def _triple(v: Sequence[float], what: str) -> list[float]:
    out = [float(x) for x in v]
    if len(out) != 3:
        raise ValueError(f"{what} needs x y z, got {len(out)} numbers")
    return out


class MapClient:
    def __init__(self, bus: Bus, participant: Any = None, name: str = "map-client", timeout: float = 5.0) -> None:
        self.rpc = RpcClient(bus, "MAP", name)
        self.participant, self.timeout = participant, timeout

    def as_of_frame(self) -> int:
        tick = context.current_tick()
        if tick is not None:
            return tick.frame
        if self.participant is not None and self.participant.frame >= 0:
            return self.participant.frame
        return -1

    def _call(self, method: str, q: map_query_t) -> map_reply_t:
        q.as_of_frame = self.as_of_frame()
        return self.rpc.call(method, q, map_reply_t, timeout=self.timeout)

    @staticmethod
    def _query(points: Iterable[Sequence[float]] = (), lo: Sequence[float] | None = None,
               hi: Sequence[float] | None = None, name: str = "", footprint: Sequence[float] = (0.0, 0.0),
               clearance: float = 0.0) -> map_query_t:
        q = map_query_t()
        q.points = [_triple(p, "a point") for p in points]
        q.num_points = len(q.points)
        q.box_min = _triple(lo, "the box's min") if lo is not None else [0.0] * 3
        q.box_max = _triple(hi, "the box's max") if hi is not None else [0.0] * 3
        q.name = name
        q.footprint = [float(footprint[0]), float(footprint[1])]
        q.clearance = float(clearance)
        return q

    def info(self) -> dict[str, Any]:
        return reply_dict(self._call("info", self._query()))

    def states(self, points: Iterable[Sequence[float]]) -> list[str]:
        """"free", "occupied" or "unknown" for each point (world frame, m)."""
        rep = self._call("state", self._query(points))
        return [STATES[s] for s in rep.states]

    def box(self, lo: Sequence[float], hi: Sequence[float]) -> dict[str, int]:
        """Voxels in the box by state."""
        rep = self._call("box", self._query(lo=lo, hi=hi))
        return {"occupied": rep.occupied, "free": rep.free, "unknown": rep.unknown}

    def free_area(self, lo: Sequence[float], hi: Sequence[float]) -> tuple[float, float]:
        """(free m2, footprint m2) of the box: the columns whose voxels in the box are all known free."""
        rep = self._call("free_area", self._query(lo=lo, hi=hi))
        return rep.free_area_m2, rep.area_m2

    def occupied(self, lo: Sequence[float], hi: Sequence[float]) -> list[tuple[float, float, float]]:
        """The centres of the occupied voxels in the box (what the motion service checks
        joint-space moves against), in key order."""
        rep = self._call("occupied", self._query(lo=lo, hi=hi))
        return [(float(v[0]), float(v[1]), float(v[2])) for v in rep.voxels]

    def free_spots(self, lo: Sequence[float], hi: Sequence[float], footprint: Sequence[float],
                   clearance: float = 0.01) -> list[tuple[float, float, float]]:
        """Where a footprint (x, y sides, m) with `clearance` around it fits in the box, by
        what the cameras saw (no occupied voxel, few unknown): centres at the box's bottom,
        row by row from its low x and y corner."""
        rep = self._call("free_spots", self._query(lo=lo, hi=hi, footprint=footprint, clearance=clearance))
        return [tuple(s) for s in rep.spots]

    def save(self, name: str) -> str:
        return self._call("save", self._query(name=name)).file

    def load(self, name: str) -> dict[str, Any]:
        return reply_dict(self._call("load", self._query(name=name)))

    def clear(self) -> dict[str, Any]:
        return reply_dict(self._call("clear", self._query()))


def reply_dict(r: map_reply_t) -> dict[str, Any]:
    return {"frame": r.frame, "resolution": r.resolution, "clouds": r.clouds, "leaves": r.leaves,
            "captures": dict(zip(r.cameras, r.captures)), **({"file": r.file} if r.file else {})}


def interface(bus: Bus, participant: Any = None, arg: str = "", **options: Any) -> MapClient:
    """The occupancy map interface of a skill process (``--interface map=skillbus.perception.
    map_client``): queries as of the asking tick's frame. `arg` is unused."""
    return MapClient(bus, participant, name=participant.name if participant is not None else "map-client")


def occupancy_map() -> MapClient | None:
    """The process's map interface, or None when it has none."""
    from skillbus.robot import interfaces
    try:
        return interfaces.get("map")
    except interfaces.InterfaceError:
        return None
