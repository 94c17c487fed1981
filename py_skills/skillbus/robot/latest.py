"""The latest message of one robot channel, decoded only when a skill asks (a tick is
rarer than a frame) and checked before it is used: one that does not decode or holds
values that are not sane is counted (`bad`, and by kind in `rejects`) and the last good
one stays. The camera's detections and the articulated objects' reading are such
channels; under lockstep the subscription is a lockstep one (a tick of frame n sees the
message of frame n), on the wall clock it is straight over the bus."""

from __future__ import annotations

from typing import Any, Callable, Generic, TypeVar

from skillbus.bus import Bus
from skillbus.msgs import decode
from skillbus.validate import BadValue, Rejects

M = TypeVar("M")


class LatestReading(Generic[M]):
    def __init__(self, bus: Bus, participant: Any, channel: str, msg_type: type, check: Callable[[Any], None],
                 kind: str) -> None:
        self.channel, self.msg_type, self.check = channel, msg_type, check
        self._seen: M | None = None
        self._raw: bytes | None = None
        self.bad = 0  # messages not used: not decodable, or values not sane (by kind: rejects)
        self.rejects = Rejects(kind)
        if participant is not None:
            participant.subscribe(channel, lambda m: self._on(m.data), latest_only=True)
        else:
            bus.subscribe(channel, lambda ch, d: self._on(d))

    def _on(self, data: bytes) -> None:
        self._raw = data

    @property
    def latest(self) -> M | None:
        """The latest good message, or None before the first."""
        if self._raw is not None:
            m = decode(self.msg_type, self._raw)
            self._raw = None
            if m is None:
                self.bad += 1
                return self._seen
            try:
                self.check(m)
            except BadValue as e:
                self.bad += 1
                self.rejects.record(self.channel, e)
                return self._seen
            self._seen = m
        return self._seen
