import hashlib
import struct

from skillbus.bus import open_bus
from skillbus.lockstep import FrameInbox, FrameOutbox, expectations_for, peek_stamp
from skillbus.log import BadInputCounter
from skillbus.msgs import channel_count_t, header_t, test_sample_t


def stamped(frame, sender, seq, value=0):
    m = test_sample_t()
    h = header_t()
    h.frame, h.sender, h.seq = frame, sender, seq
    m.header, m.i64 = h, value
    return m.encode()


def count(sender, ch, frame, n):
    c = channel_count_t()
    c.sender, c.channel, c.frame, c.count = sender, ch, frame, n
    return c


def test_peek_stamp_reads_any_message_with_a_header_first():
    s = peek_stamp(stamped(42, "wm", 7))
    assert (s.frame, s.sender, s.seq) == (42, "wm", 7)


def test_peek_stamp_rejects_truncated_and_garbage():
    b = stamped(1, "wm", 0)
    assert all(peek_stamp(b[:n]) is None for n in range(30))
    assert peek_stamp(b"\xff" * 64) is None


def test_inbox_hands_out_canonical_order_whatever_the_arrival_order():
    inbox = FrameInbox("me", BadInputCounter("t"))
    for ch, sender, seq in [("B", "p2", 1), ("A", "p2", 0), ("A", "p1", 1), ("B", "p1", 0)]:
        inbox.add(ch, stamped(3, sender, seq))
    want = [count("p1", "A", 3, 1), count("p1", "B", 3, 1), count("p2", "A", 3, 1), count("p2", "B", 3, 1)]
    assert inbox.missing(want) == ""
    order = [f"{m.stamp.sender}/{m.stamp.seq}/{m.channel}" for m in inbox.take(want, 4)]
    assert order == ["p1/0/B", "p1/1/A", "p2/0/A", "p2/1/B"]


def test_inbox_names_what_is_missing():
    inbox = FrameInbox("me", BadInputCounter("t"))
    inbox.add("SB_X", stamped(5, "p1", 0))
    assert inbox.missing([count("p1", "SB_X", 5, 2)]) == "channel SB_X from sender p1 in frame 5: got 1 of 2"


def test_inbox_drops_own_duplicate_stale_and_unstamped():
    bad = BadInputCounter("t")
    inbox = FrameInbox("me", bad)
    inbox.add("A", stamped(1, "me", 0))
    inbox.add("A", stamped(1, "p", 0))
    inbox.add("A", stamped(1, "p", 0))
    assert inbox.duplicates == 1
    assert len(inbox.take([count("p", "A", 1, 1)], 2)) == 1
    inbox.add("A", stamped(1, "p", 0))
    assert inbox.stale == 1
    inbox.add("A", b"\x01\x02\x03")
    assert bad.total == 1


def test_expectations_only_for_subscribed_channels_from_others():
    announced = [count("me", "A", 1, 1), count("p", "A", 1, 2), count("p", "B", 1, 1), count("q", "A", 1, 0)]
    e = expectations_for(announced, {"A"}, "me")
    assert [(c.sender, c.count) for c in e] == [("p", 2)]


def test_outbox_stamps_counts_and_hashes_like_the_cpp_side():
    bus = open_bus("memq://")
    sent = []
    bus.subscribe("SB_A", lambda ch, d: sent.append(d))
    out = FrameOutbox(bus, "p1")
    out.begin_frame(9, 90_000_000)
    out.publish("SB_A", test_sample_t())
    out.publish("SB_A", test_sample_t())
    while bus.handle(0):
        pass
    assert [peek_stamp(d).seq for d in sent] == [0, 1]
    assert [(c.channel, c.frame, c.count) for c in out.count_list()] == [("SB_A", 9, 2)]
    # The frame digest is SHA-256 over (u32 length + bytes) of channel and message, in order
    # (common/src/lockstep_frame.cpp computes the same).
    h = hashlib.sha256()
    for d in sent:
        h.update(struct.pack("<I", 4) + b"SB_A" + struct.pack("<I", len(d)) + d)
    assert out.finish_frame() == h.digest()


# -- what the quiet-frame core hands back (skillbus.quiet_frames) -------------------------

def participant_on_memq():
    from skillbus.lockstep import LockstepParticipant
    return LockstepParticipant(open_bus("memq://"), "me")


def test_handed_back_newest_goes_to_the_handler_a_clock_and_messages_to_pythons_path():
    p = participant_on_memq()
    got = []
    p.subscribe("SB_STATE", got.append, latest_only=True)
    p.subscribe("SB_OTHER", lambda m: None)
    assert p.latest_only == {"SB_STATE"}
    p._take_back([(0, "SB_STATE", stamped(4, "sim", 0, 7)),  # newest of frames the core acked
                  (2, "SB_OTHER", stamped(5, "sim", 0))])    # held for the frame Python takes
    assert [(m.channel, m.stamp.frame, m.stamp.sender) for m in got] == [("SB_STATE", 4, "sim")]
    assert p.inbox.missing([count("sim", "SB_OTHER", 5, 1)]) == ""
    p.subscribe("SB_STATE", got.append)  # subscribed again without it: every message again
    assert p.latest_only == set()


def test_a_latest_only_handler_that_fails_between_frames_fails_the_next_frame_naming_it():
    p = participant_on_memq()

    def broken(m):
        raise ValueError("cannot read it")

    p.subscribe("SB_STATE", broken, latest_only=True)
    p._take_back([(0, "SB_STATE", stamped(4, "sim", 0))])
    assert p._latest_failure == "handler of SB_STATE failed: ValueError: cannot read it"


def test_after_frame_hooks_keep_frames_from_the_core_unless_idle():
    p = participant_on_memq()
    p._master, p._last_ack = "clock", b"ack"

    class Hook:
        def __init__(self, idle):
            self.is_idle = idle

        def __call__(self, frame):
            pass

        def idle(self):
            return self.is_idle

    class Core:  # (a stand-in for skillbus.quiet_frames.QuietFrames: only the decision is tested)
        def usable(self):
            return True

    core = Core()
    p._quiet_made, p._quiet = True, core
    assert p._quiet_core() == (core, (2**63 - 1, 2**63 - 1))  # no callback: no horizon
    p.after_frame.append(Hook(True))
    assert p._quiet_core() is not None
    p.after_frame[0].is_idle = False
    assert p._quiet_core() is None
    p.after_frame[:] = [lambda frame: None]  # a plain hook: it always has work
    assert p._quiet_core() is None
    p.after_frame[:] = []
    p.on_frame = lambda f, t: None
    assert p._quiet_core() is None  # a frame callback without a horizon: every frame is Python's
    p.quiet_horizon = lambda: (9, 100)
    assert p._quiet_core() == (core, (9, 100))
    p.quiet_horizon = lambda: None
    assert p._quiet_core() is None
