"""The bus: publish bytes on a channel, subscribe a handler, dispatch with a timeout.

Every skillbus process talks through this interface, never through LCM directly, so the
transport is picked by URL at start-up::

    udpm://239.255.76.67:7667?ttl=0   LCM over UDP multicast (the default)
    memq://                           LCM in-process queue (unit tests)
    dds://DOMAIN                      Cyclone DDS (reserved; not built yet, clear error)

Example::

    bus = open_bus("memq://")
    bus.subscribe("SB_X", lambda channel, data: print(channel, data))
    bus.publish("SB_X", b"hello")
    bus.handle(0.1)
"""

from __future__ import annotations

import abc
import collections
import logging
import os
import re
import select
from typing import Callable

import lcm

Handler = Callable[[str, bytes], None]
DEFAULT_URL = "udpm://239.255.76.67:7667?ttl=0"
DEFAULT_QUEUE_CAPACITY = 10000  # LCM's default of 30 silently drops bursts

log = logging.getLogger("bus")


class BusError(RuntimeError):
    pass


class Bus(abc.ABC):
    @abc.abstractmethod
    def publish(self, channel: str, data: bytes) -> None: ...

    @abc.abstractmethod
    def subscribe(self, channel: str, handler: Handler,
                  queue_capacity: int = DEFAULT_QUEUE_CAPACITY) -> int: ...

    @abc.abstractmethod
    def unsubscribe(self, subscription_id: int) -> None: ...

    @abc.abstractmethod
    def handle(self, timeout: float) -> bool:
        """Dispatches pending messages, waiting at most ``timeout`` seconds for the first.
        Returns True if a message was handled."""

    @property
    @abc.abstractmethod
    def url(self) -> str: ...


def resolve_url(url: str | None = None) -> str:
    return url or os.environ.get("SKILLBUS_BUS_URL") or DEFAULT_URL


def channel(name: str) -> str:
    """Namespaced channel name: $SKILLBUS_NAMESPACE + name (several robots on one bus)."""
    return os.environ.get("SKILLBUS_NAMESPACE", "") + name


def open_bus(url: str | None = None) -> Bus:
    url = resolve_url(url)
    scheme = url.split("://", 1)[0] if "://" in url else ""
    if scheme in ("udpm", "memq", "file", "tcpq"):
        return LcmBus(url)
    if scheme == "dds":
        raise BusError(f"bus URL '{url}': the Cyclone DDS backend is not built into this version")
    raise BusError(f"bus URL '{url}': unknown scheme (expected udpm://, memq:// or dds://)")


_UDPM = re.compile(r"^udpm://([^:/?]*)(?::(\d+))?(\?.*)?$")


def lane_of(channel: str) -> int:
    """Lane 1 for many-to-one channels (names ending in _ACK or _JOIN), else lane 0."""
    return 1 if channel.endswith(("_ACK", "_JOIN")) else 0


def lane1_url(url: str) -> str:
    """URL of lane 1 for a udpm:// URL (same group, port+1); "" when the URL has one lane."""
    m = _UDPM.match(url)
    if not m:
        return ""
    port = int(m.group(2)) if m.group(2) else 7667
    return f"udpm://{m.group(1) or '239.255.76.67'}:{port + 1}{m.group(3) or ''}"


class LcmBus(Bus):
    """LCM backend with two lanes (same design as common/src/lcm_bus.hpp).

    LCM's UDP multicast wakes every process on a group and port for every datagram.
    Many-to-one channels (lockstep acks and joins) therefore travel on lane 1, the same
    group on port+1, which only their receiver listens to; everything else uses lane 0.
    """

    def __init__(self, url: str) -> None:
        self._url = url
        self._lane_urls = [url, lane1_url(url)]
        self._lanes: list[lcm.LCM | None] = [None, None]
        self._lane_subs = [0, 0]
        self._subs: dict[int, tuple[int, lcm.LCMSubscription]] = {}
        self._next_id = 1
        self._lane(0)  # fail early, with a clear message

    def _lane(self, i: int) -> lcm.LCM:
        if not self._lane_urls[i]:
            i = 0
        lane = self._lanes[i]
        if lane is None:
            try:
                lane = self._lanes[i] = lcm.LCM(self._lane_urls[i])
            except (RuntimeError, OSError) as e:
                raise BusError(f"cannot open LCM at '{self._lane_urls[i]}' (for udpm:// the host needs a "
                               f"multicast route, e.g. `ip route add 224.0.0.0/4 dev lo`): {e}") from e
        return lane

    @property
    def url(self) -> str:
        return self._url

    def publish(self, channel: str, data: bytes) -> None:
        self._lane(lane_of(channel)).publish(channel, data)

    def subscribe(self, channel: str, handler: Handler,
                  queue_capacity: int = DEFAULT_QUEUE_CAPACITY) -> int:
        def guarded(ch: str, data: bytes) -> None:
            # A failing handler is logged; the dispatch loop goes on (never crash on input).
            try:
                handler(ch, data)
            except Exception:
                log.exception("handler for %s failed", ch)

        lane = lane_of(channel) if self._lane_urls[1] else 0
        sub = self._lane(lane).subscribe(channel, guarded)
        sub.set_queue_capacity(queue_capacity)
        sid = self._next_id
        self._next_id += 1
        self._subs[sid] = (lane, sub)
        self._lane_subs[lane] += 1
        return sid

    def unsubscribe(self, subscription_id: int) -> None:
        entry = self._subs.pop(subscription_id, None)
        if entry is not None:
            lane, sub = entry
            self._lane(lane).unsubscribe(sub)
            self._lane_subs[lane] -= 1

    def handle(self, timeout: float) -> bool:
        ms = max(0, int(timeout * 1000 + 0.999))
        if self._lane_subs[1] == 0 or self._lane_subs[0] == 0:
            r = self._lane(1 if self._lane_subs[0] == 0 and self._lane_subs[1] else 0).handle_timeout(ms)
            if r < 0:
                raise BusError(f"LCM dispatch failed on {self._url}")
            return r > 0
        lanes = [self._lane(0), self._lane(1)]
        ready, _, _ = select.select(lanes, [], [], ms / 1000)
        handled = False
        for lane in ready:
            handled |= lane.handle_timeout(0) > 0
        return handled


class DropEveryNthBus(Bus):
    """Drops every n-th message published on each channel (tests of retries and loss),
    or only on the given channels."""

    def __init__(self, inner: Bus, n: int, channels: set[str] | None = None) -> None:
        self.inner, self.n, self.channels = inner, n, channels
        self.published: collections.Counter[str] = collections.Counter()
        self.dropped = 0

    @property
    def url(self) -> str:
        return self.inner.url

    def publish(self, channel: str, data: bytes) -> None:
        self.published[channel] += 1
        if self.n > 0 and self.published[channel] % self.n == 0 and (
                self.channels is None or channel in self.channels):
            self.dropped += 1
            return
        self.inner.publish(channel, data)

    def subscribe(self, channel: str, handler: Handler,
                  queue_capacity: int = DEFAULT_QUEUE_CAPACITY) -> int:
        return self.inner.subscribe(channel, handler, queue_capacity)

    def unsubscribe(self, subscription_id: int) -> None:
        self.inner.unsubscribe(subscription_id)

    def handle(self, timeout: float) -> bool:
        return self.inner.handle(timeout)
