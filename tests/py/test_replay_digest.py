"""The console's replay of a log (skillbus.console.replay): the session digest is made of
what participants published in their frames, not of the protocol's acks and joins that a
recorder of both lanes (or of DDS) also keeps; and a system behind $SKILLBUS_NAMESPACE
replays as the same system without it."""

from pathlib import Path

from skillbus.console.replay import ReplayLog
from skillbus.dds_record import LogWriter
from skillbus.lockstep_wire import AckEncoder
from skillbus.msgs import channel_count_t, header_t, lockstep_clock_t, lockstep_join_t, test_sample_t

FRAMES = 6


def stamped(frame: int, sender: str, seq: int, text: str) -> bytes:
    m = test_sample_t()
    m.header = header_t()
    m.header.frame, m.header.sim_time_ns, m.header.sender, m.header.seq = frame, frame * 20_000_000, sender, seq
    m.text = text
    return m.encode()


def session_log(path: Path, *, acks: bool, ns: str = "") -> Path:
    """A master "sim" and a participant "dev": each frame the master publishes one state,
    the participant two messages (seq 0 and 1) in even frames and none in odd ones; the
    next clock announces them. The acks come after the frame's messages, or before them
    (the recorder reads the two lanes' sockets in turn)."""
    out = LogWriter(path)
    acker = AckEncoder("dev")
    if acks:
        join = lockstep_join_t()
        join.participant, join.kind, join.pid = "dev", "python", 1
        out.write(ns + "SB_LOCKSTEP_JOIN", join.encode())
    counts: list[channel_count_t] = []
    for f in range(FRAMES):
        c = lockstep_clock_t()
        c.header = header_t()
        c.header.frame, c.header.sim_time_ns, c.header.sender = f, f * 20_000_000, "sim"
        c.frame_period_ns, c.participants, c.num_participants = 20_000_000, ["dev"], 1
        c.counts, c.num_counts = counts, len(counts)
        out.write(ns + "SB_LOCKSTEP_CLOCK", c.encode())
        ack = acker.encode(f, f * 20_000_000, [], bytes(32), "")  # (stamped frame f, sender dev, seq 0)
        if acks and f == 2:
            out.write(ns + "SB_LOCKSTEP_ACK", ack)
        out.write(ns + "SB_TEST_STATE", stamped(f, "sim", 0, f"state {f}"))
        if f % 2 == 0:
            out.write(ns + "SB_TEST_CMD", stamped(f, "dev", 0, f"cmd {f}"))
            out.write(ns + "SB_TEST_CMD", stamped(f, "dev", 1, f"more {f}"))
        if acks and f != 2:
            out.write(ns + "SB_LOCKSTEP_ACK", ack)
        counts = []
        for sender, ch, n in (("sim", "SB_TEST_STATE", 1), ("dev", "SB_TEST_CMD", 2 if f % 2 == 0 else 0)):
            cc = channel_count_t()
            cc.sender, cc.channel, cc.frame, cc.count = sender, ns + ch, f, n
            counts.append(cc)
    out.close()
    return path


def test_the_protocols_acks_and_joins_are_not_part_of_the_session(tmp_path):
    plain = ReplayLog(session_log(tmp_path / "plain.lcmlog", acks=False))
    both_lanes = ReplayLog(session_log(tmp_path / "acks.lcmlog", acks=True))
    assert plain.frames == both_lanes.frames == list(range(FRAMES))
    assert plain.missing == both_lanes.missing == {}
    assert both_lanes.digest == plain.digest


def test_a_namespaced_system_replays_as_the_same_system(tmp_path, monkeypatch):
    plain = ReplayLog(session_log(tmp_path / "plain.lcmlog", acks=True))
    monkeypatch.setenv("SKILLBUS_NAMESPACE", "lab_")
    apart = ReplayLog(session_log(tmp_path / "lab.lcmlog", acks=True, ns="lab_"))
    assert apart.frames == plain.frames and apart.missing == {}
    # (the channels themselves carry the namespace, so the digest differs, as the run's would)
    assert apart.digest != plain.digest and len(apart.digest) == 64
