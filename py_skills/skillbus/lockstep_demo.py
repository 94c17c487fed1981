"""The Python participant of the lockstep demo world (C++ twin: common/apps/sb_demo_participant.cpp).

Each frame it folds SB_DEMO_STATE (from the clock) and the other participants'
SB_DEMO_CMD into its state, in the order they are handled, and publishes SB_DEMO_CMD
with the result, so any arrival-order dependence would change the session digest.
"""

from __future__ import annotations

import json
import sys
import time

from skillbus.bus import DropEveryNthBus, channel, open_bus
from skillbus.lockstep import LockstepParticipant, StampedMessage, ack_channel
from skillbus.msgs import decode, test_sample_t

MASK = (1 << 64) - 1


def demo_mix(state: int, value: int) -> int:
    """Same as common/apps/demo_mix.hpp, on unsigned 64-bit integers."""
    state ^= value & MASK
    state = (state * 0x100000001B3) & MASK
    state ^= state >> 29
    return state


def to_int64(u: int) -> int:
    return u - (1 << 64) if u >= 1 << 63 else u


class DemoParticipant:
    def __init__(self, participant: LockstepParticipant, drop_at_frame: int = -1,
                 slow_at_frame: int = -1, slow_s: float = 0.8, every: int = 1) -> None:
        self.p = participant
        self.slow_at_frame, self.slow_s, self.every = slow_at_frame, slow_s, every
        self.state = 0
        self.received = 0
        self.drop_at_frame = drop_at_frame
        self.cmd_channel = channel("SB_DEMO_CMD")
        participant.subscribe(channel("SB_DEMO_STATE"), self.fold)
        participant.subscribe(self.cmd_channel, self.fold)
        participant.on_frame = self.on_frame

    def fold(self, m: StampedMessage) -> None:
        s = decode(test_sample_t, m.data)
        if s is None:  # it passed the lockstep checks, so a sender is broken: fail the frame
            raise ValueError(f"{m.channel} from {m.stamp.sender} in frame {m.stamp.frame} is not a test_sample_t")
        self.state = demo_mix(self.state, s.i64)
        self.received += 1

    def on_frame(self, frame: int, sim_time_ns: int) -> None:
        if frame % self.every:
            return  # (tests: traffic in some frames only)
        if frame == self.slow_at_frame:
            # Test: a slow frame, longer than the master's clock resend interval, spent
            # dispatching the bus as a long synchronous RPC call would.
            end = time.monotonic() + self.slow_s
            while time.monotonic() < end:
                self.p.bus.handle(0.05)
        out = test_sample_t()
        out.blob = bytes(4)  # LCM's Python default b"" would encode 4 bytes short
        out.i64 = to_int64(demo_mix(self.state, frame))
        out.text = self.p.name
        if frame == self.drop_at_frame:
            # Count it as published but never send it: receivers must report the loss.
            real_publish = self.p.bus.publish
            self.p.bus.publish = lambda ch, data: None  # type: ignore[method-assign]
            self.p.publish(self.cmd_channel, out)
            self.p.bus.publish = real_publish  # type: ignore[method-assign]
            return
        self.p.publish(self.cmd_channel, out)


class Listener:
    """A participant with nothing to do but hear SB_DEMO_CMD (tests: frames quiet but for
    the ones with a message for it): it folds what it hears, publishes nothing."""

    def __init__(self, participant: LockstepParticipant) -> None:
        self.state = self.received = 0
        participant.subscribe(channel("SB_DEMO_CMD"), self.fold)

    def fold(self, m: StampedMessage) -> None:
        s = decode(test_sample_t, m.data)
        if s is None:
            raise ValueError(f"{m.channel} from {m.stamp.sender} in frame {m.stamp.frame} is not a test_sample_t")
        self.state = demo_mix(self.state, s.i64 ^ m.stamp.frame)
        self.received += 1


class LatestReader:
    """A participant that reads only the newest SB_DEMO_STATE (a latest-only subscription)
    and acts in every N-th frame: it publishes SB_DEMO_CMD mixing that state with the
    frame (tests: the frames between are acked by the quiet-frame core, which hands it the
    newest state; the digest must be Python's own)."""

    def __init__(self, participant: LockstepParticipant, every: int) -> None:
        self.p, self.every = participant, every
        self.state = self.received = 0
        self.newest: StampedMessage | None = None
        self.cmd_channel = channel("SB_DEMO_CMD")
        participant.subscribe(channel("SB_DEMO_STATE"), self.keep, latest_only=True)
        participant.on_frame = self.on_frame
        participant.quiet_horizon = self.horizon
        self.last_frame = -1

    def keep(self, m: StampedMessage) -> None:
        self.newest = m

    def horizon(self) -> tuple[int, int] | None:
        if self.last_frame < 0:
            return None
        nxt = (self.last_frame // self.every + 1) * self.every  # the next frame that acts
        return (nxt - 1, 2**63 - 1) if nxt - 1 > self.last_frame else None

    def on_frame(self, frame: int, sim_time_ns: int) -> None:
        self.last_frame = frame
        if frame % self.every or self.newest is None:
            return
        s = decode(test_sample_t, self.newest.data)
        if s is None:
            raise ValueError(f"SB_DEMO_STATE from {self.newest.stamp.sender} is not a test_sample_t")
        self.state = demo_mix(self.state, s.i64 ^ self.newest.stamp.frame)
        self.received += 1
        out = test_sample_t()
        out.blob = bytes(4)
        out.i64 = to_int64(demo_mix(self.state, frame))
        out.text = self.p.name
        self.p.publish(self.cmd_channel, out)


def main(args) -> int:
    # Options the chosen mode would ignore without a word: refused, naming them.
    for given, needs, flag in ((args.frames is not None, args.wall_clock, "--frames needs --wall-clock (under lockstep "
                                "the master sets the frames)"),
                               (args.listen, args.bare, "--listen needs --bare")):
        if given and not needs:
            print(f"error: lockstep-participant: {flag}", file=sys.stderr)
            return 2
    bus = open_bus(args.url)
    if args.lose_acks_every:
        bus = DropEveryNthBus(bus, args.lose_acks_every, {ack_channel()})
    p = LockstepParticipant(bus, args.name, kind="python-demo", wall_clock=args.wall_clock,
                            wall_frames=args.frames, clock_timeout=args.clock_timeout,
                            message_timeout=args.message_timeout)
    if args.latest_every:
        demo = LatestReader(p, args.latest_every)
    else:
        demo = None if args.bare else DemoParticipant(p, args.drop_at_frame, args.slow_at_frame, args.slow_s,
                                                      args.every)
    listener = Listener(p) if args.bare and args.listen else None
    r = p.run()
    received = demo.received if demo else listener.received if listener else 0
    state = demo.state if demo else listener.state if listener else 0
    rejected = getattr(bus, "rejected", {})
    print(json.dumps({"ok": r.ok, "error": r.error, "name": args.name, "frames": r.frames,
                      "received": received, "state": state, "digest": r.digest_hex,
                      "bad_input": p.bad_input.total, "quiet_frames": p.quiet_frames,
                      "rejected": {k: v for k, v in rejected.items() if k != "ok"},
                      "core_rejected": p.quiet_core_rejected()}), flush=True)
    return 0 if r.ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
