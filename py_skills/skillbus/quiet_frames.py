"""Quiet lockstep frames acknowledged without the interpreter (docs/lockstep.md).

A participant with nothing to do in a frame (no ``on_frame``, nothing to run after it,
nothing held for it, no message it subscribed to announced by the clock) still takes the
clock and sends a signed ack. In Python that is most of a bare frame's cost. While such a
participant waits for its next clock, ``skillbus_native.QuietFrames`` (C++,
common/python/quiet_frames.hpp) reads its bus socket, acks quiet frames itself (the same
bytes and running digest as Python) and returns at the first datagram that is anything
else, which Python then handles on its usual path.

It takes over only what it can do exactly as Python does: the udpm:// bus read on the
caller's thread (skillbus.udpm), signed with the deployment's key or open. Elsewhere
(dds://, a test's wrapping bus, the module not built, ``SKILLBUS_QUIET_FRAMES=0``)
``for_bus`` answers None and the participant waits in Python.
"""

from __future__ import annotations

import logging
import os
from typing import Any

from skillbus.bus import AuthenticatedBus, Bus, LcmBus

log = logging.getLogger("lockstep")

ENV = "SKILLBUS_QUIET_FRAMES"


def _native() -> Any:
    try:
        import skillbus_native  # built by CMake into the build tree (common/python)
    except ImportError as e:
        log.info("quiet lockstep frames go through Python: skillbus_native is not built (%s; make build)", e)
        return None
    return skillbus_native


class QuietFrames:
    """The native core for one participant on one bus, and the way back into the bus for
    the datagrams it returns."""

    def __init__(self, core: Any, lcm_bus: LcmBus, auth_bus: AuthenticatedBus | None, clock_channel: str) -> None:
        self.core, self._lcm, self._auth = core, lcm_bus, auth_bus
        self._clock_channel = clock_channel
        self._rejected: dict[str, int] = {}

    def set_subscribed(self, channels: set[str]) -> None:
        self.core.set_subscribed(sorted(channels))

    def feed(self, datagram: bytes, sender: object) -> None:
        """A datagram the core returned, to the bus's handlers (verified when signed)."""
        (self._auth or self._lcm).feed_datagram(datagram, sender)

    def note_rejected(self) -> None:
        """Clocks the core dropped (forged, stale, replayed, forbidden), counted with the
        bus's own."""
        if self._auth is None:
            return
        for reason, total in self.core.rejected().items():
            new = total - self._rejected.get(reason, 0)
            if new > 0:
                self._auth.note_rejected(reason, self._clock_channel, new)
                self._rejected[reason] = total


def for_bus(bus: Bus, name: str, clock_channel: str, ack_channel: str) -> QuietFrames | None:
    """The quiet-frame core for participant `name` on `bus`, or None where it cannot act
    exactly as Python would (see the module's doc)."""
    if os.environ.get(ENV, "1") == "0":
        return None
    auth_bus = bus if type(bus) is AuthenticatedBus else None
    lcm_bus = auth_bus.inner if auth_bus is not None else bus
    if type(lcm_bus) is not LcmBus:
        return None
    fd = lcm_bus.lane0_socket()
    if fd is None:
        return None
    native = _native()
    if native is None:
        return None
    keys: list[bytes] = []
    identity, policy_text = "", ""
    if auth_bus is not None:
        keys, identity = auth_bus.keys, auth_bus.identity
        rules = auth_bus._rules
        if rules is not None:
            policy_text = "\n".join(f"{r.pattern} {' '.join(sorted(r.identities))}" for r in rules.rules) or "#"
    try:
        core = native.QuietFrames(fd, clock_channel, ack_channel, lcm_bus.lane1_url, name, keys, identity,
                                  policy_text)
    except RuntimeError as e:
        log.info("quiet lockstep frames go through Python: %s", e)
        return None
    return QuietFrames(core, lcm_bus, auth_bus, clock_channel)
