"""Message authentication (skillbus.auth) and the bus policy (skillbus.policy), in process:
what verifies, and every way a message is refused and counted."""

from __future__ import annotations

import os
import stat

import pytest

from skillbus import auth
from skillbus.bus import AuthenticatedBus, open_bus
from skillbus.policy import Policy, PolicyError

KEY, OTHER = bytes(range(32)), bytes(range(1, 33))


class Clock:
    def __init__(self, t: int = 1_700_000_000 * 10**9) -> None:
        self.t = t

    def __call__(self) -> int:
        return self.t


def pair(policy=None, clock=None):
    clock = clock or Clock()
    return auth.Sealer(KEY, "skills", clock=clock), auth.Opener([KEY], policy=policy, clock=clock), clock


def test_a_sealed_message_opens_to_its_payload_and_sender():
    s, o, _ = pair()
    sealed = s.seal("SB_X", b"payload")
    assert sealed.startswith(b"payload") and sealed.endswith(auth.MAGIC)
    opened = o.open("SB_X", sealed)
    assert (opened.payload, opened.identity) == (b"payload", "skills")
    assert o.stats["ok"] == 1


@pytest.mark.parametrize("tamper, reason", [
    (lambda s, data: b"payload", "unsigned"),                                  # no trailer
    (lambda s, data: data[:-1] + b"X", "unsigned"),                            # a broken marker
    (lambda s, data: b"Payload" + data[7:], "bad_mac"),                        # the payload changed
    (lambda s, data: auth.Sealer(OTHER, "skills").seal("SB_X", b"payload"), "bad_mac"),  # another key
    (lambda s, data: s.seal("SB_Y", b"payload"), "bad_mac"),                   # moved to another channel
    (lambda s, data: data[:5] + data[6:], "bad_mac"),                           # a byte cut out
    (lambda s, data: data[-40:], "unsigned"),                                   # only the end
    (lambda s, data: b"", "unsigned"),
])
def test_a_message_that_does_not_verify_is_refused_and_counted(tamper, reason):
    s, o, _ = pair()
    data = s.seal("SB_X", b"payload")
    with pytest.raises(auth.Rejected) as e:
        o.open("SB_X", tamper(s, data))
    assert e.value.reason == reason
    assert o.stats[reason] == 1 and o.stats["ok"] == 0


def test_a_replayed_message_is_refused_even_out_of_order():
    s, o, _ = pair()
    first, second, third = (s.seal("SB_X", b"%d" % i) for i in range(3))
    o.open("SB_X", third)
    o.open("SB_X", first)  # late, but new: accepted (UDP lanes may reorder)
    for again in (first, third):
        with pytest.raises(auth.Rejected, match="replayed"):
            o.open("SB_X", again)
    o.open("SB_X", second)
    assert o.stats["replayed"] == 2 and o.stats["ok"] == 3


def test_a_message_older_than_the_window_is_stale_and_a_restarted_sender_is_heard():
    clock = Clock()
    s, o, _ = pair(clock=clock)
    old = s.seal("SB_X", b"old")
    clock.t += int(31e9)
    with pytest.raises(auth.Rejected, match="stale"):
        o.open("SB_X", old)
    # A restarted sender (a new incarnation, its counter from 1 again) is not a replay.
    o.open("SB_X", s.seal("SB_X", b"a"))
    restarted = auth.Sealer(KEY, "skills", clock=clock)
    o.open("SB_X", restarted.seal("SB_X", b"b"))
    assert o.stats["ok"] == 2


def test_far_behind_the_highest_counter_is_a_replay():
    s, o, _ = pair()
    first = s.seal("SB_X", b"first")
    for _ in range(auth.REPLAY_WINDOW + 1):
        last = s.seal("SB_X", b"x")
    o.open("SB_X", last)
    with pytest.raises(auth.Rejected, match="replayed"):
        o.open("SB_X", first)


def test_the_policy_decides_who_sends_on_a_channel():
    policy = Policy.parse("SB_LOCKSTEP_CLOCK sim\nSB_*_REQ *\n")
    s, o, _ = pair(policy=policy)
    with pytest.raises(auth.Rejected, match="forbidden: skills may not send on SB_LOCKSTEP_CLOCK"):
        o.open("SB_LOCKSTEP_CLOCK", s.seal("SB_LOCKSTEP_CLOCK", b"clock"))
    o.open("SB_WM_REQ", s.seal("SB_WM_REQ", b"q"))
    with pytest.raises(auth.Rejected, match="forbidden"):  # no rule: refused
        o.open("SB_OTHER", s.seal("SB_OTHER", b"?"))


def test_policy_errors_name_the_line():
    with pytest.raises(PolicyError, match="line 2: 'SB_X' names a channel and no identity"):
        Policy.parse("SB_A a\nSB_X\n")
    with pytest.raises(PolicyError, match="line 1: 'SB-X' is not a channel name"):
        Policy.parse("SB-X a\n")


def test_the_shipped_policy_matches_the_systems_own_programs():
    from skillbus import paths
    p = Policy.load(paths.REPO_ROOT / "deploy" / "policy.conf")
    assert p.allows("sim", "SB_LOCKSTEP_CLOCK") and not p.allows("operator", "SB_LOCKSTEP_CLOCK")
    assert p.allows("skills", "SB_ROBOT_ARM_CMD") and not p.allows("operator", "SB_ROBOT_ARM_CMD")
    assert p.allows("skill_mgr", "SB_SKPROC_SKILLS_REQ") and not p.allows("skills", "SB_SKPROC_SKILLS_REQ")
    assert p.allows("wm", "SB_WM_CHANGES") and not p.allows("skills", "SB_WM_CHANGES")
    assert p.allows("operator", "SB_WM_REQ") and p.allows("operator", "SB_SKILL_REQ")


def test_key_files_are_private_and_rotate(tmp_path):
    path = auth.create_key_file(tmp_path / "k" / "bus.key")
    assert stat.S_IMODE(path.stat().st_mode) == 0o600 and stat.S_IMODE(path.parent.stat().st_mode) == 0o700
    (first,) = auth.load_keys(path)
    auth.create_key_file(path, rotate=True)
    new, old = auth.load_keys(path)
    assert old == first and new != first
    # The new key signs; a receiver with both keys still verifies the old one's messages.
    o = auth.Opener([new, old], clock=Clock())
    o.open("SB_X", auth.Sealer(old, "a", clock=o.clock).seal("SB_X", b"x"))
    o.open("SB_X", auth.Sealer(new, "b", clock=o.clock).seal("SB_X", b"x"))
    os.chmod(path, 0o644)
    with pytest.raises(auth.KeyFileError, match="readable or writable by others.*chmod 600"):
        auth.load_keys(path)
    with pytest.raises(auth.KeyFileError, match="skillbus key create"):
        auth.load_keys(tmp_path / "missing.key")


def test_strip_reads_a_logged_message_without_verifying():
    s, _, _ = pair()
    assert auth.strip(s.seal("SB_X", b"abc")) == b"abc"
    assert auth.strip(b"plain") == b"plain"


def test_the_bus_signs_and_delivers_only_what_verifies(tmp_path, monkeypatch):
    key = auth.create_key_file(tmp_path / "bus.key")
    monkeypatch.setenv(auth.KEY_ENV, str(key))
    bus = open_bus("memq://")
    assert isinstance(bus, AuthenticatedBus)
    got = []
    bus.subscribe("SB_X", lambda ch, data: got.append(data))
    bus.publish("SB_X", b"signed")
    bus.inner.publish("SB_X", b"forged")  # straight onto the transport: no authenticator
    while bus.handle(0.05):
        pass
    assert got == [b"signed"]
    assert bus.rejected["unsigned"] == 1 and bus.rejected["ok"] == 1


def test_skillbus_key_creates_rotates_and_retires(tmp_path, capsys):
    from skillbus.cli import main
    path = tmp_path / "bus.key"
    assert main(["key", "create", "--path", str(path)]) == 0
    (first,) = auth.load_keys(path)
    assert main(["key", "create", "--path", str(path)]) == 0 and auth.load_keys(path) == [first]  # kept
    assert main(["key", "rotate", "--path", str(path)]) == 0
    new, old = auth.load_keys(path)
    assert old == first
    assert main(["key", "retire", "--path", str(path)]) == 0 and auth.load_keys(path) == [new]
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    os.chmod(path, 0o640)
    assert main(["key", "show", "--path", str(path)]) == 1
    assert "chmod 600" in capsys.readouterr().err


def test_an_identity_the_trailer_cannot_hold_is_refused_not_cut(monkeypatch, tmp_path):
    # Before, a 300-byte identity was cut to 255 bytes: every receiver saw another identity
    # than the policy's and dropped every message as forbidden, while the sender's own
    # policy check (on the whole identity) passed.
    from skillbus.bus import BusError
    for bad in ("i" * 256, "é" * 128, ""):
        with pytest.raises(ValueError, match=r"is \d+ bytes: an identity is 1 to 255 bytes \(\$SKILLBUS_IDENTITY\)"):
            auth.Sealer(KEY, bad)
    auth.Sealer(KEY, "i" * 255)
    key = auth.create_key_file(tmp_path / "bus.key")
    monkeypatch.setenv("SKILLBUS_KEY_FILE", str(key))
    monkeypatch.setenv("SKILLBUS_IDENTITY", "x" * 300)
    with pytest.raises(BusError, match="is 300 bytes"):
        open_bus("memq://")
    with pytest.raises(PolicyError, match="longer than 255 bytes"):
        Policy.parse("SB_X " + "y" * 256 + "\n")
