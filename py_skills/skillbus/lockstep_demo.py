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


def main(args) -> int:
    bus = open_bus(args.url)
    if args.lose_acks_every:
        bus = DropEveryNthBus(bus, args.lose_acks_every, {ack_channel()})
    p = LockstepParticipant(bus, args.name, kind="python-demo", wall_clock=args.wall_clock,
                            wall_frames=args.frames, clock_timeout=args.clock_timeout,
                            message_timeout=args.message_timeout)
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
