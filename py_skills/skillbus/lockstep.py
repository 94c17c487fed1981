"""The lockstep participant in Python (protocol: docs/lockstep.md).

A participant joins the clock master by name; for every frame n it

1. waits for ``clock(n)``, which lists what everyone published since the last clock;
2. waits until it holds every listed message on the channels it subscribed to, and hands
   them to its handlers in canonical order (frame, sender, seq), never arrival order;
3. runs ``on_frame(n, sim_time_ns)``, where it publishes its outputs stamped n;
4. acknowledges n with what it published per channel and a SHA-256 of it.

A message that never arrives is an error naming the channel, sender and frame. In
wall-clock mode the same code runs without a master, on a local timer.

Example::

    p = LockstepParticipant(open_bus(), "planner")
    p.subscribe("SB_DEMO_STATE", lambda m: print(m.stamp.frame, len(m.data)))
    p.on_frame = lambda frame, t: p.publish("SB_DEMO_CMD", test_sample_t())
    result = p.run()
"""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import os
import struct
import time
from typing import Any, Callable

from skillbus.bus import Bus, channel
from skillbus.log import BadInputCounter
from skillbus import tick_context as context
from skillbus.validate import BadValue, integer
from skillbus.lockstep_wire import AckEncoder, decode_clock, read_header
from skillbus.msgs import channel_count_t, header_t, lockstep_clock_t, lockstep_join_t
from skillbus import quiet_frames
from skillbus.quiet_frames import QuietFrames


def clock_channel() -> str:
    return channel("SB_LOCKSTEP_CLOCK")


def ack_channel() -> str:
    return channel("SB_LOCKSTEP_ACK")


def join_channel() -> str:
    return channel("SB_LOCKSTEP_JOIN")


@dataclasses.dataclass(frozen=True)
class Stamp:
    frame: int
    sim_time_ns: int
    sender: str
    seq: int


@dataclasses.dataclass
class StampedMessage:
    channel: str
    stamp: Stamp
    data: bytes


@dataclasses.dataclass
class RunResult:
    ok: bool = True
    error: str = ""
    frames: int = 0
    sim_time_ns: int = 0
    wall_seconds: float = 0.0
    digest: bytes = bytes(32)

    @property
    def digest_hex(self) -> str:
        return self.digest.hex()


class LockstepError(RuntimeError):
    pass


def peek_stamp(data: bytes) -> Stamp | None:
    """Reads the header_t that every lockstep message carries right after its fingerprint."""
    if len(data) < 33:
        return None
    try:
        h, _ = read_header(data, 8)
    except (ValueError, struct.error):
        return None
    if not h.sender or h.seq < 0 or h.frame < 0 or h.sim_time_ns < 0:  # (sim time starts at 0)
        return None
    return Stamp(h.frame, h.sim_time_ns, h.sender, h.seq)


def _str_bytes(s: str | bytes) -> bytes:
    b = s.encode() if isinstance(s, str) else s
    return struct.pack("<I", len(b)) + b


class FrameOutbox:
    """Stamps, counts and hashes what one process publishes in a frame."""

    def __init__(self, bus: Bus, sender: str) -> None:
        self.bus, self.sender = bus, sender
        self.frame, self.sim_time_ns, self.seq = -1, 0, 0
        self.counts: dict[str, int] = {}
        self._hash = hashlib.sha256()

    def begin_frame(self, frame: int, sim_time_ns: int) -> None:
        self.frame, self.sim_time_ns, self.seq = frame, sim_time_ns, 0
        self.counts = {}
        self._hash = hashlib.sha256()

    def publish(self, ch: str, msg: Any) -> None:
        h = header_t()
        h.frame, h.sim_time_ns, h.sender, h.seq = self.frame, self.sim_time_ns, self.sender, self.seq
        msg.header = h
        self.seq += 1
        data = msg.encode()
        self.bus.publish(ch, data)
        self.counts[ch] = self.counts.get(ch, 0) + 1
        self._hash.update(_str_bytes(ch))
        self._hash.update(_str_bytes(data))

    def count_list(self) -> list[channel_count_t]:
        out = []
        for ch in sorted(self.counts):
            c = channel_count_t()
            c.sender, c.channel, c.frame, c.count = self.sender, ch, self.frame, self.counts[ch]
            out.append(c)
        return out

    def finish_frame(self) -> bytes:
        return self._hash.digest()


class FrameInbox:
    """Holds stamped messages until everything announced for a frame is there."""

    def __init__(self, me: str, bad: BadInputCounter) -> None:
        self.me, self.bad = me, bad
        self.held: dict[tuple[str, str, int], dict[int, StampedMessage]] = {}
        self.floor = -1
        self.duplicates = self.stale = 0

    def add(self, ch: str, data: bytes) -> None:
        s = peek_stamp(data)
        if s is None:
            self.bad.record(ch, "no lockstep header (frame, sender, seq)", len(data))
            return
        if s.sender == self.me:
            return
        if s.frame < self.floor:
            self.stale += 1
            return
        slot = self.held.setdefault((ch, s.sender, s.frame), {})
        if s.seq in slot:
            self.duplicates += 1
            return
        slot[s.seq] = StampedMessage(ch, s, data)

    def missing(self, expected: list[channel_count_t]) -> str:
        for e in expected:
            got = len(self.held.get((e.channel, e.sender, e.frame), ()))
            if got < e.count:
                return (f"channel {e.channel} from sender {e.sender} in frame {e.frame}: "
                        f"got {got} of {e.count}")
        return ""

    def take(self, expected: list[channel_count_t], floor: int) -> list[StampedMessage]:
        out: list[StampedMessage] = []
        for e in expected:
            slot = self.held.pop((e.channel, e.sender, e.frame), None)
            if slot:
                out.extend(slot.values())
        out.sort(key=lambda m: (m.stamp.frame, m.stamp.sender, m.stamp.seq))
        self.floor = max(self.floor, floor)
        for key in [k for k in self.held if k[2] < self.floor]:
            self.stale += len(self.held.pop(key))
        return out


def expectations_for(announced: list[channel_count_t], subscribed: set[str], me: str) -> list[channel_count_t]:
    return [c for c in announced if c.sender != me and c.count > 0 and c.channel in subscribed]


MessageHandler = Callable[[StampedMessage], None]
FrameCallback = Callable[[int, int], None]
# (last frame, sim time before which) the frame callback would do nothing, or None; with
# a third element, watches: {latest-only channel: FingerWatch bounds} the newest message
# of each of those channels must keep for a frame to stay quiet (skillbus.quiet_frames)
QuietHorizon = Callable[[], "tuple[int, int] | tuple[int, int, dict] | None"]
NO_HORIZON = (2**63 - 1, 2**63 - 1)


class LockstepParticipant:
    def __init__(self, bus: Bus, name: str, *, kind: str = "python", wall_clock: bool = False,
                 message_timeout: float = 2.0, clock_timeout: float = 10.0, join_interval: float = 0.1,
                 wall_frame_period_ns: int = 10_000_000, wall_frames: int | None = None) -> None:
        if not name:
            raise ValueError("a lockstep participant needs a name")
        self.bus, self.name, self.kind, self.wall_clock = bus, name, kind, wall_clock
        self.message_timeout, self.clock_timeout, self.join_interval = message_timeout, clock_timeout, join_interval
        self.wall_frame_period_ns, self.wall_frames = wall_frame_period_ns, wall_frames
        self.log = logging.getLogger(f"lockstep {name}")
        self.bad_input = BadInputCounter(f"lockstep {name}")
        self.outbox = FrameOutbox(bus, name)
        self._acks = AckEncoder(name)
        self.inbox = FrameInbox(name, self.bad_input)
        self.handlers: dict[str, MessageHandler] = {}
        self.latest_only: set[str] = set()  # channels whose handler keeps only the newest message
        self.on_frame: FrameCallback | None = None
        # With on_frame: how far the next frames would do nothing in it, given no message
        # that gives them work (skillbus.quiet_frames acks them without Python); None: every
        # frame goes through Python. Asked before each wait.
        self.quiet_horizon: QuietHorizon | None = None
        self.previous_frame: tuple[int, int] = (-1, 0)  # (frame, sim time) acked before the current one
        self._acked_sim_time = 0
        self._latest_failure = ""  # a latest-only handler that failed between frames
        self._subs: list[int] = []
        self._next_clock: lockstep_clock_t | None = None
        self._ack_channel, self._join_channel = ack_channel(), join_channel()
        self._master = ""  # the master whose clock we follow (from the first clock)
        self._stop_seen, self._stop_reason = False, ""
        self._master_restarted = ""  # the error, once a restarted master's join phase is heard in a session
        self._last_acked, self._last_ack = -1, b""
        self._current = -1  # the frame being worked on (its clock may be resent meanwhile)
        self._last_sim_time = 0  # sim time of the last clock taken: it never runs backwards
        self._master_heard = 0.0  # monotonic time of the last resend of the clock we acked
        self._running = bytes(32)
        self._stop_requested = False
        self._held: list[tuple[int, str, Any]] = []  # (due frame, channel, message): from ticks
        # Run after each frame's ack. One with an idle() that answers True has nothing to do
        # after the next frames, and does not keep them from the quiet-frame core.
        self.after_frame: list[Callable[[int], None]] = []
        self._quiet: QuietFrames | None = None  # (skillbus.quiet_frames; made at the first wait)
        self._quiet_made = False
        self._join_bytes = b""  # our join, sent again as a sign of life while a frame takes long
        self.quiet_frames = 0  # frames acked by that core
        self._quiet_stale = (0, 0)  # its stale and duplicate latest-only messages, counted
        if not wall_clock:
            self._subs.append(bus.subscribe(clock_channel(), self._on_clock))

    # -- API ---------------------------------------------------------------
    def subscribe(self, ch: str, handler: MessageHandler, latest_only: bool = False) -> None:
        """Lockstep subscription to an exact channel name.

        `latest_only`: the handler only keeps the newest message (a state published every
        frame, read when a tick or a later frame needs it). It may then be given only the
        newest of several frames' messages, when this participant next runs: frames whose
        only messages are on such channels are acked without the interpreter
        (skillbus.quiet_frames)."""
        first = ch not in self.handlers
        self.handlers[ch] = handler
        if latest_only:
            self.latest_only.add(ch)
        else:
            self.latest_only.discard(ch)
        if first:
            self._subs.append(self.bus.subscribe(ch, self._on_stamped))
        if self._quiet is not None:
            self._quiet.set_subscribed(set(self.handlers), self.latest_only)

    def publish(self, ch: str, msg: Any) -> None:
        """Publishes for the current frame (from on_frame or a message handler).

        In a skill process answering a manager's tick of frame n (between its own
        frames, at a moment that varies from run to run) the message is held and goes
        out at the start of this participant's frame n + 1, which always comes after the
        tick: the same frame on every run."""
        tick = context.current_tick() if not self.wall_clock else None
        if tick is not None:
            self._held.append((tick.frame + 1, ch, msg))
            return
        self.outbox.publish(ch, msg)

    def _publish_held(self, frame: int) -> None:
        due = [(ch, m) for f, ch, m in self._held if f <= frame]
        self._held = [h for h in self._held if h[0] > frame]
        for ch, m in due:
            self.outbox.publish(ch, m)

    @property
    def frame(self) -> int:
        return self.outbox.frame

    @property
    def acked_sim_time_ns(self) -> int:
        """The sim time of the last frame acknowledged (0 before the first)."""
        return self._acked_sim_time

    @property
    def completed_frame(self) -> int:
        """The last frame this participant finished and acknowledged (-1 before the first)."""
        return self._last_acked

    def stop(self) -> None:
        self._stop_requested = True

    def close(self) -> None:
        for s in self._subs:
            self.bus.unsubscribe(s)
        self._subs = []

    def run(self) -> RunResult:
        if self.wall_clock:
            return self._run_wall_clock()
        try:
            return self._run_lockstep()
        finally:
            if self._quiet is not None:  # (the core's last counts, into the bus's, for the summary)
                self._quiet.note_counts()

    # -- bus callbacks -----------------------------------------------------
    def _on_stamped(self, ch: str, data: bytes) -> None:
        if not self.wall_clock:
            self.inbox.add(ch, data)
            return
        s = peek_stamp(data)
        if s is None:
            self.bad_input.record(ch, "no lockstep header (frame, sender, seq)", len(data))
        elif s.sender != self.name:
            self.handlers[ch](StampedMessage(ch, s, data))  # wall clock: on arrival

    def _on_clock(self, ch: str, data: bytes) -> None:
        try:
            c = decode_clock(data)  # (the hottest path of a frame: skillbus.lockstep_wire)
        except ValueError:
            c = None
        if c is None:
            self.bad_input.record(ch, "not a lockstep_clock_t", len(data))
            return
        # Only the clock of our session counts: it lists us, and comes from the master
        # that sent the first one we accepted.
        if self.name not in c.participants:
            self.bad_input.record(ch, f"a clock from '{c.header.sender}' that does not list {self.name}",
                                  len(data))
            return
        if not self._master:
            self._master = c.header.sender
        if c.header.sender != self._master:
            self.bad_input.record(ch, f"a clock from '{c.header.sender}', not from our master "
                                      f"'{self._master}'", len(data))
            return
        if c.stop:
            self._stop_seen, self._stop_reason = True, c.stop_reason
            return
        frame = c.header.frame
        if frame < 0:  # the master waits for participants to join
            if self._last_acked < 0 and self._current < 0 and self._next_clock is None:
                self._master_heard = time.monotonic()  # before our first frame: it is alive, we wait on
                return
            # Within a session: the master started again (killed and restarted), and the
            # session is lost. Said now, naming it, rather than after the clock timeout.
            self._master_restarted = (f"lockstep: master {self._master} started again after frame "
                                      f"{self._last_acked} (it waits for participants to join): this "
                                      "session is lost")
            self._stop_seen, self._next_clock = True, None
            return
        if frame == self._last_acked and self._last_ack:
            # The master resends the clock while a participant is still at work on the
            # frame: it is alive, so this one waits on (a slow participant's frame may be long).
            self._master_heard = time.monotonic()
            self.bus.publish(self._ack_channel, self._last_ack)  # our ack was lost, or not yet counted
            return
        if frame == self._current and frame == self._last_acked + 1:
            # The master resends the clock of the frame this participant works on (a long
            # one: a synchronous call that dispatches the bus): a join tells it we are
            # alive, or it would take us for dead after its ack timeout.
            if self._join_bytes:
                self.bus.publish(self._join_channel, self._join_bytes)
            return
        if frame <= self._last_acked or frame == self._current:
            return  # a resend of the clock of the frame we are working on
        if frame != self._last_acked + 1:
            self.bad_input.record(ch, f"a clock for frame {frame} while frame {self._last_acked + 1} is due",
                                  len(data))
            return
        if self._next_clock is None:  # else: a resend of the clock we already hold
            try:
                self._check_clock(c)
            except BadValue as e:
                self.bad_input.record(ch, f"a clock for frame {frame} with {e}", len(data))
                return
            self._next_clock = c
            self._last_sim_time = c.header.sim_time_ns

    def _check_clock(self, c: lockstep_clock_t) -> None:
        """The values of the next frame's clock, before anything acts on them: its sim time
        (what on_frame gets: a device steps its fingers by the difference, so a time that
        runs backwards would move them the wrong way) and its counts (a negative count, or
        one for a frame after this clock's, is no count of published messages)."""
        integer(c.header.sim_time_ns, "sim_time_ns", self._last_sim_time)
        for i, n in enumerate(c.counts):
            integer(n.count, f"counts[{i}].count", 0)
            integer(n.frame, f"counts[{i}].frame", 0, c.header.frame)

    # -- waiting for the clock -----------------------------------------------
    def _horizon(self) -> tuple[int, int] | None:
        """How far the core may ack frames for this participant: everywhere without a
        frame callback; with one, as far as its quiet_horizon says (None: not now)."""
        if self.on_frame is None:
            return NO_HORIZON
        return self.quiet_horizon() if self.quiet_horizon is not None else None

    def _quiet_core(self) -> tuple[QuietFrames, tuple[int, int]] | None:
        """skillbus.quiet_frames' core, and its horizon, while this participant's next
        frames may have nothing to do but take the clock and ack: nothing to run after a
        frame, nothing held for one, a frame callback only with a horizon (the messages
        it subscribed to the core checks per clock)."""
        if self._held or self._stop_requested or not self._master or not self._last_ack:
            return None
        if any(not getattr(after, "idle", lambda: False)() for after in self.after_frame):
            return None
        horizon = self._horizon()
        if horizon is None:
            return None
        if not self._quiet_made:
            self._quiet_made = True
            self._quiet = quiet_frames.for_bus(self.bus, self.name, clock_channel(), self._ack_channel)
            if self._quiet is not None:
                self._quiet.set_subscribed(set(self.handlers), self.latest_only)
        if self._quiet is None or not self._quiet.usable():
            return None
        return self._quiet, horizon

    def _wait_for_clock(self, timeout: float) -> int:
        """Handles the bus for at most `timeout` while the next clock is awaited; the
        number of quiet frames acked meanwhile without Python (0 on Python's path)."""
        found = self._quiet_core()
        if found is None:
            if self._quiet is not None:
                self._take_back(self._quiet.core.release())  # (what it held is Python's again)
            self.bus.handle(timeout)
            return 0
        q, (through_frame, before_ns, *watches) = found
        q.set_watches(watches[0] if watches else {})
        try:  # what the inbox holds for coming frames on latest-only channels, the core's to place
            for key in [k for k in self.inbox.held if k[0] in self.latest_only]:
                slot = self.inbox.held[key]
                for seq in list(slot):
                    q.core.hold(key[0], slot[seq].data, self._last_acked)
                    del slot[seq]
                del self.inbox.held[key]
        except RuntimeError as e:  # (more than a frame's traffic: Python's path, its inbox's rules)
            self.log.warning("quiet frames: %s", e)
            self._take_back(q.core.release())
            self.bus.handle(timeout)
            return 0
        (datagram, sender, acked, last_acked, sim_time, last_ack, running, resends, handed) = q.core.wait(
            timeout, self._master, self._last_acked, self._last_sim_time, self._last_ack, self._running,
            through_frame, before_ns)
        if acked:
            self._last_acked = self._current = last_acked
            self._last_sim_time, self._last_ack, self._running = sim_time, last_ack, running
            self._acked_sim_time = sim_time
            self.outbox.begin_frame(last_acked, sim_time)
            self.inbox.take([], last_acked)  # (as each frame's take: what is older is stale)
        if resends:
            self._master_heard = time.monotonic()
        q.note_counts_now_and_then()
        if handed:
            self._take_back(handed)
        if datagram is not None:
            q.feed(datagram, sender)
        return acked

    def _take_back(self, handed: list[tuple[int, str, bytes]]) -> None:
        """What the quiet-frame core hands back, verified: the newest message of a channel
        in frames it acked (to the handler, as the frames would have), the clock of a
        frame it was collecting and that frame's messages (on Python's usual path)."""
        for kind, ch, payload in handed:
            if kind == 0:
                stamp = peek_stamp(payload)
                try:
                    self.handlers[ch](StampedMessage(ch, stamp, payload))  # type: ignore[arg-type]
                except Exception as e:  # (failed between frames: the next frame fails, naming it)
                    self.log.exception("handler of %s failed", ch)
                    self._latest_failure = self._latest_failure or f"handler of {ch} failed: {type(e).__name__}: {e}"
            elif kind == 1:
                self._on_clock(ch, payload)
            else:
                self._on_stamped(ch, payload)
        if self._quiet is not None:
            stats = self._quiet.core.latest_stats()
            self.inbox.stale += stats["stale"] - self._quiet_stale[0]
            self.inbox.duplicates += stats["duplicates"] - self._quiet_stale[1]
            self._quiet_stale = (stats["stale"], stats["duplicates"])

    def quiet_core_rejected(self) -> dict[str, int]:
        """Messages the quiet-frame core dropped, by reason (counted in the bus's too)."""
        if self._quiet is None:
            return {}
        self._quiet.note_counts()
        return {k: v for k, v in self._quiet.core.counts().items() if k != "ok"}

    # -- loops -------------------------------------------------------------
    def _send_ack(self, frame: int, sim_time_ns: int, error: str) -> None:
        digest = self.outbox.finish_frame()
        self._last_ack = self._acks.encode(frame, sim_time_ns, self.outbox.count_list(), digest, error)
        self._last_acked, self._acked_sim_time = frame, sim_time_ns
        self.bus.publish(self._ack_channel, self._last_ack)
        self._running = hashlib.sha256(self._running + digest).digest()

    def _fail(self, r: RunResult, error: str) -> RunResult:
        r.ok, r.error = False, error
        self.log.error("%s", error)
        r.digest = self._running
        return r

    def _run_lockstep(self) -> RunResult:
        r = RunResult()
        join = lockstep_join_t()
        join.participant, join.kind, join.pid = self.name, self.kind, os.getpid()
        join_bytes = self._join_bytes = join.encode()
        last_event = time.monotonic()
        next_join = last_event
        while self._next_clock is None and not self._stop_seen:
            now = time.monotonic()
            if now - max(last_event, self._master_heard) > self.clock_timeout:
                return self._fail(r, "lockstep: joined, but no clock from the master, nor word that it waits for "
                                     f"the others to join, within {self.clock_timeout:.1f} s (no master on this bus?)")
            if now >= next_join:
                self.bus.publish(self._join_channel, join_bytes)
                next_join = now + self.join_interval
            self.bus.handle(0.01)
        wall_start = time.monotonic()
        subscribed = set(self.handlers)
        while not self._stop_requested:
            last_event = time.monotonic()
            while self._next_clock is None and not self._stop_seen:
                if time.monotonic() - max(last_event, self._master_heard) > self.clock_timeout:
                    return self._fail(r, f"lockstep: no clock after frame {self._last_acked} within "
                                         f"{self.clock_timeout:.1f} s (master {self._master} gone?)")
                quiet = self._wait_for_clock(0.05)
                if quiet:
                    self.quiet_frames += quiet
                    r.frames += quiet
                    r.sim_time_ns = self._last_sim_time
                    last_event = time.monotonic()
            if self._next_clock is None:
                break  # stopped
            clk, self._next_clock = self._next_clock, None
            frame, sim_time = clk.header.frame, clk.header.sim_time_ns
            self._current = frame
            expected = expectations_for(clk.counts, subscribed, self.name)
            deadline = time.monotonic() + self.message_timeout
            miss = self.inbox.missing(expected)
            while miss and not self._stop_seen:
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                self.bus.handle(min(left, 0.05))
                miss = self.inbox.missing(expected)
            if self._stop_seen:
                break
            self.outbox.begin_frame(frame, sim_time)
            if miss:
                err = f"message lost on {miss} (noticed by {self.name})"
                self._send_ack(frame, sim_time, err)
                return self._fail(r, "lockstep: " + err)
            failure = ""
            self.previous_frame = (self._last_acked, self._acked_sim_time)
            try:
                if self._latest_failure:
                    raise LockstepError(self._latest_failure)
                self._publish_held(frame)
                for m in self.inbox.take(expected, frame):
                    self.handlers[m.channel](m)
                if self.on_frame is not None:
                    self.on_frame(frame, sim_time)
            except Exception as e:  # the frame fails with a message; the master stops the run
                self.log.exception("frame %d failed", frame)
                failure = f"frame handler failed: {type(e).__name__}: {e}"
            self._send_ack(frame, sim_time, failure)
            if failure:
                return self._fail(r, f"lockstep: {self.name} in frame {frame}: {failure}")
            r.frames += 1
            r.sim_time_ns = sim_time
            for after in self.after_frame:
                after(frame)
        if self._master_restarted:
            return self._fail(r, self._master_restarted)
        if self._stop_seen and self._stop_reason:
            return self._fail(r, f"lockstep stopped by the master: {self._stop_reason}")
        r.digest = self._running
        r.wall_seconds = time.monotonic() - wall_start
        return r

    def _run_wall_clock(self) -> RunResult:
        r = RunResult()
        start = time.monotonic()
        period = self.wall_frame_period_ns * 1e-9
        frame = 0
        anchor = start  # frame 0's due time, moved on when the loop falls behind
        while not self._stop_requested and (self.wall_frames is None or frame < self.wall_frames):
            due = anchor + frame * period
            # Behind by more than a frame (a long frame, a stalled machine): the missed
            # frames are not run back to back; the schedule starts again from now.
            if (late := time.monotonic() - due) > period:
                anchor += late
                due += late
            while (left := due - time.monotonic()) > 0:
                self.bus.handle(left)
            sim_time = frame * self.wall_frame_period_ns
            self.outbox.begin_frame(frame, sim_time)
            if self.on_frame is not None:
                self.on_frame(frame, sim_time)
            self._running = hashlib.sha256(self._running + self.outbox.finish_frame()).digest()
            frame += 1
            r.frames, r.sim_time_ns = frame, sim_time
        r.digest = self._running
        r.wall_seconds = time.monotonic() - start
        return r
