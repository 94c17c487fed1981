"""CAN in lockstep: a canopen Network whose traffic is paced by lockstep frames.

A CAN bus is a second path between lockstep participants, beside LCM, and the same rule
must hold on it: what one process sends in frame n reaches the others at frame n + 1,
never earlier or later depending on timing. The link does for CAN frames what the
lockstep inbox does for LCM messages:

* Everything canopen sends goes through the link (it is the Network's ``bus``). At the
  end of each frame the link announces how many frames it put on the bus (can_sync_t on
  SB_CAN_SYNC, itself a lockstep message).
* A reader thread queues what arrives. At the start of frame n + 1 the link hands canopen
  exactly the announced number of frames, in arrival order (one sender per bus keeps its
  order; the hub keeps order per sender), waiting for stragglers up to a timeout.
* Sends made while a skill process answers a tick of frame n (outside its own frames)
  are held and go out at the start of its frame n + 1, which always comes after the tick.
* SDO (COB-IDs 0x580 + node, 0x600 + node: request and answer, configuration before the
  run) is passed on at once and not counted; nothing else may be sent outside the frames.

Periodic sends (canopen's heartbeat producer) are disabled: a device under lockstep sends
its heartbeat from its frames, by sim time.
"""

from __future__ import annotations

import collections
import logging
import os
import struct
import threading
import time
from typing import Callable

import can
import canopen

from skillbus.bus import channel
from skillbus.lockstep import LockstepError, LockstepParticipant, StampedMessage
from skillbus.msgs import can_sync_t, decode
from skillbus import tick_context as context
from skillbus.validate import BadValue, Rejects, integer

log = logging.getLogger("can-lockstep")
# The most CAN frames one sender may announce for one lockstep frame: more than a second
# of a saturated 1 Mbit/s bus (about 9,000 frames). A larger count is not traffic, and
# waiting for it would stall the next frame until the timeout.
MAX_SYNC_FRAMES = 10_000


def sync_channel() -> str:
    return channel("SB_CAN_SYNC")


def sdo_ids(node_id: int) -> set[int]:
    return {0x580 + node_id, 0x600 + node_id}


class _NoPeriodicTask:
    """What send_periodic returns under lockstep: periodic sends are the frames' job."""

    def stop(self) -> None:
        pass

    def modify_data(self, msg) -> None:
        pass


class LockstepCanLink:
    def __init__(self, participant: LockstepParticipant, bus: can.BusABC, can_channel: str,
                 network: canopen.Network, out_of_band: set[int], timeout: float = 2.0) -> None:
        # The bus by name, not by where its socket happens to be: it is in the digest.
        self.p, self.real, self.can_channel, self.network = participant, bus, os.path.basename(can_channel), network
        self.out_of_band, self.timeout = set(out_of_band), timeout
        self.channel_info = f"lockstep link on {getattr(bus, 'channel_info', can_channel)}"
        network.bus = self
        self._queue: collections.deque[can.Message] = collections.deque()
        self._cv = threading.Condition()
        self._expected: list[tuple[str, int]] = []   # (sender, frames) announced for the next frame
        self._held: list[tuple[int, can.Message]] = []  # (due frame, message): sends from ticks
        self._sent = 0
        self._hub_losses_seen = getattr(bus, "hub_losses", 0)
        self.stats = {"sent": 0, "received": 0, "out_of_band": 0}
        self.rejects = Rejects("can-lockstep")  # announcements and frames not acted on
        self._stop = False
        self._reader = threading.Thread(target=self._read, name="can-lockstep-reader", daemon=True)
        self._reader.start()
        self._sync_channel = sync_channel()  # (named once: published on every frame with sends)
        participant.subscribe(self._sync_channel, self._on_sync)

    # -- the python-can surface canopen uses ------------------------------------------------
    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if msg.arbitration_id in self.out_of_band:
            self.stats["out_of_band"] += 1
            self.real.send(msg, timeout)
            return
        tick = context.current_tick()
        if tick is not None:  # a skill's tick of frame n: out at the start of our frame n + 1
            # A copy: canopen sends a PDO map's own buffer, which the next send overwrites.
            held = can.Message(arbitration_id=msg.arbitration_id, data=bytes(msg.data), is_extended_id=msg.is_extended_id,
                               is_remote_frame=msg.is_remote_frame, dlc=msg.dlc, is_fd=msg.is_fd)
            self._held.append((tick.frame + 1, held))
            return
        self.real.send(msg, timeout)
        self._sent += 1

    def send_periodic(self, msg, period, *args, **kwargs) -> _NoPeriodicTask:
        return _NoPeriodicTask()

    def shutdown(self) -> None:
        self._stop = True
        self._reader.join(timeout=1.0)
        self.real.shutdown()

    # -- frames ------------------------------------------------------------------------------
    def _read(self) -> None:
        failing = False
        while not self._stop:
            try:
                msg = self.real.recv(0.1)
            except can.CanError as e:  # (a lost frame then ends the session, naming the bus)
                if not failing:
                    log.warning("CAN receive failed: %s", e)
                failing = True
                time.sleep(0.1)
                continue
            failing = False
            if msg is None or msg.is_error_frame:
                continue
            if msg.arbitration_id in self.out_of_band:
                self._notify(msg)  # (this thread must survive any frame)
                continue
            with self._cv:
                self._queue.append(msg)
                self._cv.notify_all()

    def _notify(self, msg: can.Message) -> None:
        """Hands canopen one frame. A frame its handlers cannot unpack (too short for what
        its COB-ID carries: struct.error and the like) is counted and dropped: under
        lockstep the exception would fail the frame and end the session, in the reader
        thread it would end the thread. Other errors (a CAN send that fails) still fail
        the frame, naming their cause."""
        try:
            self.network.notify(msg.arbitration_id, msg.data, msg.timestamp)
        except (struct.error, ValueError, IndexError) as e:
            self.rejects.record(f"CAN 0x{msg.arbitration_id:03X}", BadValue("frame", bytes(msg.data),
                                                                           f"{type(e).__name__}: {e}"))

    def _on_sync(self, m: StampedMessage) -> None:
        s = decode(can_sync_t, m.data)
        if s is None:
            self.rejects.record(m.channel, "not a can_sync_t")
            return
        if s.can_channel != self.can_channel:
            return
        try:
            frames = integer(s.frames, "frames", 0, MAX_SYNC_FRAMES)
        except BadValue as e:
            self.rejects.record(m.channel, e)
            return
        if frames > 0:
            self._expected.append((m.stamp.sender, frames))

    # A hub lost this recently may still explain lost frames: this process may have
    # reconnected to the restarted hub frames ago while the sender had not yet (its frames
    # went nowhere), so "since the last frame" alone missed it (the fault suite saw it).
    RECENT_HUB_LOSS_S = 10.0

    def _hub_note(self) -> str:
        """Why frames may have been lost: the CAN hub went away since the last frame whose
        frames all arrived, or within the last RECENT_HUB_LOSS_S seconds (it may be back
        already: a restarted hub loses what was in flight). Only the message says so: the
        run's frames and digest do not depend on it."""
        last = getattr(self.real, "last_loss_at", None)
        recent = isinstance(last, float) and time.monotonic() - last < self.RECENT_HUB_LOSS_S
        if (getattr(self.real, "hub_losses", 0) == self._hub_losses_seen and getattr(self.real, "fault", None) is None
                and not recent):
            return ""
        return f" (the CAN hub went away meanwhile: CAN hub gone: {getattr(self.real, 'path', self.can_channel)})"

    def begin_frame(self, frame: int) -> None:
        """Hands canopen the CAN frames the others announced in the last frame (call first
        in on_frame), then sends what ticks held for this frame."""
        for sender, n in self._expected:
            deadline = time.monotonic() + self.timeout
            got = []
            with self._cv:
                while len(got) < n:
                    if self._queue:
                        got.append(self._queue.popleft())
                        continue
                    left = deadline - time.monotonic()
                    if left <= 0:
                        raise LockstepError(f"CAN frames lost on {self.can_channel}: {sender} announced {n} in frame "
                                            f"{frame - 1}, {len(got)} arrived within {self.timeout:.1f} s"
                                            + self._hub_note())
                    self._cv.wait(left)
            for msg in got:
                self.stats["received"] += 1
                self._notify(msg)
        self._expected = []
        self._hub_losses_seen = getattr(self.real, "hub_losses", 0)
        due = [m for f, m in self._held if f <= frame]
        self._held = [(f, m) for f, m in self._held if f > frame]
        for msg in due:
            self.real.send(msg)
            self._sent += 1

    def idle(self) -> bool:
        """Nothing announced or held for the next frame: its begin and end would do nothing
        unless a CAN sync announces frames (a message that gives that frame work)."""
        return not self._expected and not self._held and not self._sent

    def end_frame(self) -> None:
        """Announces this frame's sends (call last in on_frame)."""
        if self._sent:
            s = can_sync_t()
            s.can_channel, s.frames = self.can_channel, self._sent
            self.p.publish(self._sync_channel, s)
            self.stats["sent"] += self._sent
        self._sent = 0

    def wrap(self, on_frame: Callable[[int, int], None] | None) -> Callable[[int, int], None]:
        """on_frame with the link's begin and end around it."""
        def framed(frame: int, sim_time_ns: int) -> None:
            self.begin_frame(frame)
            if on_frame is not None:
                on_frame(frame, sim_time_ns)
            self.end_frame()
        return framed
