"""Quiet lockstep frames acknowledged without the interpreter (docs/lockstep.md).

A participant with nothing to do in a frame (no ``on_frame``, nothing to run after it,
nothing held for it, no message it subscribed to announced by the clock) still takes the
clock and sends a signed ack. In Python that is most of a bare frame's cost. While such a
participant waits for its next clock, ``skillbus_native.QuietFrames`` (C++,
common/python/quiet_frames.hpp) reads its bus socket, acks quiet frames itself (the same
bytes and running digest as Python) and returns at the first datagram that is anything
else, which Python then handles on its usual path.

Latest-only subscriptions (``LockstepParticipant.subscribe(..., latest_only=True)``: a
handler that only keeps the newest message, like a robot state published every frame)
do not give a frame work: the core collects and verifies the frame's messages on them as
the inbox would, acks the frame, and hands Python the newest of each channel when it
next wakes (``Handed``). A participant with a frame callback gives a horizon
(``LockstepParticipant.quiet_horizon``): how far its next frames would do nothing.

It takes over only what it can do exactly as Python does: the udpm:// bus read on the
caller's thread (skillbus.udpm), signed with the deployment's key or open. Elsewhere
(dds://, a test's wrapping bus, the module not built, ``SKILLBUS_NATIVE=0``)
``for_bus`` answers None and the participant waits in Python.
"""

from __future__ import annotations

import logging
import time
from typing import Any

from skillbus import native
from skillbus.bus import AuthenticatedBus, Bus, LcmBus

log = logging.getLogger("lockstep")


class QuietFrames:
    """The native core for one participant on one bus, and the way back into the bus for
    the datagrams it returns."""

    def __init__(self, core: Any, lcm_bus: LcmBus, auth_bus: AuthenticatedBus | None, clock_channel: str,
                 fd: int) -> None:
        self.core, self._lcm, self._auth = core, lcm_bus, auth_bus
        self._clock_channel, self._fd = clock_channel, fd
        self._counts: dict[tuple[str, str], int] = {}
        self._latest: list[str] = []  # the latest-only channels the core collects
        self._next_note = 0.0
        self._lost_sends = 0
        self._watching = False

    def usable(self) -> bool:
        """Still the bus it was made for: the same one socket read, and the participant
        the only one here hearing the clock and the latest-only channels the core
        collects (it consumes those datagrams)."""
        lcm = self._lcm
        return (lcm.lane0_socket() == self._fd and lcm.subscribers(self._clock_channel) == 1
                and all(lcm.subscribers(ch) == 1 for ch in self._latest))

    def set_subscribed(self, channels: set[str], latest_only: set[str] = frozenset()) -> None:
        """What gives a frame work; `latest_only` (of those) the core may collect itself,
        where the participant is this bus's only subscriber (the core takes the datagrams)."""
        self._latest = sorted(ch for ch in latest_only if self._lcm.subscribers(ch) == 1)
        self.core.set_subscribed(sorted(channels))
        self.core.set_latest_only(self._latest)

    def set_watches(self, watches: dict) -> None:
        """The bounds the newest message of a latest-only sim_state_t channel must keep for
        a frame to stay quiet ({channel: FingerWatch's fields after the channel}: common/
        python/finger_watch.hpp); set before each wait, {} for none. A watch on a channel
        the core does not collect changes nothing: its messages give frames work anyway."""
        if not watches and not self._watching:
            return
        self.core.clear_watches()
        for channel, bounds in watches.items():
            self.core.set_finger_watch(channel, *bounds)
        self._watching = bool(watches)

    def feed(self, datagram: bytes, sender: object) -> None:
        """A datagram the core returned, to the bus's handlers (verified when signed)."""
        (self._auth or self._lcm).feed_datagram(datagram, sender)

    NOTE_EVERY_S = 0.25  # (reading the core's counts at every wait was a few per cent of a frame)

    def note_counts_now_and_then(self) -> None:
        """note_counts, at most every NOTE_EVERY_S: refusals are logged that much later."""
        now = time.monotonic()
        if now >= self._next_note:
            self._next_note = now + self.NOTE_EVERY_S
            self.note_counts()

    def note_counts(self) -> None:
        """What the core verified, dropped (forged, stale, replayed, forbidden messages)
        and could not send, counted and logged with the bus's own, by channel."""
        lost = self.core.lost_sends()
        if lost > self._lost_sends:
            self._lcm.lost_sends += lost - self._lost_sends
            self._lost_sends = lost
            log.warning("sending on SB_LOCKSTEP_ACK failed: ack lost (%d in all from the quiet-frame core)", lost)
        if self._auth is None:
            return
        for (what, channel), total in self.core.verdicts().items():
            new = total - self._counts.get((what, channel), 0)
            if new > 0:
                self._counts[(what, channel)] = total
                self._auth.note_verified(what, channel, new)


def for_bus(bus: Bus, name: str, clock_channel: str, ack_channel: str) -> QuietFrames | None:
    """The quiet-frame core for participant `name` on `bus`, or None where it cannot act
    exactly as Python would (see the module's doc)."""
    auth_bus = bus if type(bus) is AuthenticatedBus else None
    lcm_bus = auth_bus.inner if auth_bus is not None else bus
    if type(lcm_bus) is not LcmBus:
        return None
    fd = lcm_bus.lane0_socket()
    if fd is None:
        return None
    lib = native.module()
    if lib is None:
        return None
    opener, key, identity = None, None, b""
    if auth_bus is not None:
        opener, key = auth_bus.native_opener, auth_bus.keys[0]
        if opener is None or auth_bus.refused(ack_channel):
            return None  # (a rule only Python can run; acks the policy forbids: Python names why)
        identity = auth_bus.identity.encode("utf-8", "surrogateescape")
    try:
        core = lib.QuietFrames(fd, clock_channel, ack_channel, lcm_bus.lane1_url, name, opener, key, identity)
    except (RuntimeError, ValueError, UnicodeError) as e:
        log.info("quiet lockstep frames go through Python: %s", e)
        return None
    q = QuietFrames(core, lcm_bus, auth_bus, clock_channel, fd)
    return q if q.usable() else None
