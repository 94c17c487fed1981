"""A bus that carries nothing, for unit tests of the console's parts (their handlers are
called by the test): it keeps the subscriptions, so a test can see what is heard and
deliver a message to it. A stand-in only in unit tests; the integration tests run the
real buses."""

from __future__ import annotations


class StandInBus:
    def __init__(self) -> None:
        self.n = 0
        self.subs: dict[int, tuple[str, object]] = {}

    def subscribe(self, channel, handler, **options) -> int:
        self.n += 1
        self.subs[self.n] = (channel, handler)
        return self.n

    def unsubscribe(self, sid) -> None:
        self.subs.pop(sid, None)

    def publish(self, channel, data) -> None:
        pass

    def deliver(self, channel: str, data: bytes) -> bool:
        """`data` to every subscription of a channel ending in `channel`; whether one heard it."""
        heard = [h for ch, h in list(self.subs.values()) if ch.endswith(channel)]
        for h in heard:
            h(channel, data)
        return bool(heard)
