"""The bus's authentication in C++ (skillbus_native.Sealer/Opener, used by AuthenticatedBus
when the module is built) against skillbus.auth's Python Sealer and Opener: the same
messages give the same verdicts, payloads and identities, and each verifies the other's."""

import random
import struct

import pytest

import skillbus_native
from skillbus import auth, native
from skillbus.policy import Policy

KEY, OTHER = bytes(range(32)), bytes(range(1, 33))
POLICY = "SB_LOCKSTEP_CLOCK clock\nr2/SB_ROBOT_* r2_skills\nSB_ROBOT_ARM_CMD skills\nSB_* *\n"


def messages(rng: random.Random) -> list[tuple[str, bytes, str]]:
    """(channel, bytes, what) in an order with every kind of refusal among good ones."""
    ids = ["clock", "skills", "r2_skills", "intruder", "gr\u00fcn"]
    sealers = {i: auth.Sealer(KEY, i) for i in ids}
    old = auth.Sealer(KEY, "skills", clock=lambda: 1_000_000_000)  # sent in 1970: stale
    wrong = auth.Sealer(OTHER, "skills")
    channels = ["SB_LOCKSTEP_CLOCK", "SB_DEMO_CMD", "r2/SB_ROBOT_ARM_CMD", "r1/SB_ROBOT_ARM_CMD", "NS_SB_X", "OTHER"]
    out, sent = [], []
    for _ in range(400):
        ch = rng.choice(channels)
        payload = rng.randbytes(rng.randrange(0, 300))
        kind = rng.choice(["good", "good", "good", "replay", "wrong", "stale", "unsigned", "tampered", "cut",
                           "bad_length"])
        if kind == "replay" and sent:
            c, d = rng.choice(sent)
            out.append((c, d, kind))
            continue
        if kind == "wrong":
            d = wrong.seal(ch, payload)
        elif kind == "stale":
            d = old.seal(ch, payload)
        elif kind == "unsigned":
            d = payload
        else:
            d = sealers[rng.choice(ids)].seal(ch, payload)
            if kind == "tampered" and payload:
                d = bytes([d[0] ^ 1]) + d[1:]
            elif kind == "cut":
                d = d[rng.randrange(0, len(d)):]
            elif kind == "bad_length":
                d = d[:-6] + struct.pack("<H", rng.randrange(0, 65536)) + d[-4:]
            else:
                sent.append((ch, d))
        out.append((ch, d, kind))
    return out


def verdict(opener, ch: str, data: bytes):
    try:
        o = opener.open(ch, data)
        return ("ok", o.payload, o.identity)
    except auth.Rejected as r:
        return (r.reason, r.identity)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("with_policy", [False, True])
def test_the_cpp_opener_gives_pythons_verdict_on_every_message(monkeypatch, seed, with_policy):
    monkeypatch.setenv("SKILLBUS_NAMESPACE", "NS_")
    policy = Policy.parse(POLICY) if with_policy else None
    py = auth.Opener([OTHER, KEY], policy=policy)
    cpp = auth.NativeOpener(skillbus_native, [OTHER, KEY], None if policy is None else policy.text())
    for ch, data, what in messages(random.Random(seed)):
        assert verdict(cpp, ch, data) == verdict(py, ch, data), (what, ch)
    assert cpp.stats == py.stats
    assert set(py.stats) >= {"ok", "unsigned", "bad_mac", "stale", "replayed"} | ({"forbidden"} if with_policy else set())


def test_python_verifies_what_cpp_signs_and_counters_go_up():
    s = skillbus_native.Sealer(KEY, "gr\u00fcn".encode())
    py = auth.Opener([KEY])
    for i in range(50):
        assert py.open("SB_X", s.seal("SB_X", bytes([i]) * i)).payload == bytes([i]) * i
    assert py.stats == {"ok": 50}
    assert s.incarnation > 0


def test_bad_arguments_are_refused_naming_why():
    with pytest.raises(ValueError, match="1 to 255 bytes"):
        skillbus_native.Sealer(KEY, b"")
    with pytest.raises(ValueError, match="at least one key"):
        skillbus_native.Opener([], None)
    with pytest.raises(ValueError, match="names a channel and no identity"):
        skillbus_native.Opener([KEY], "SB_X\n")
    with pytest.raises(TypeError):
        skillbus_native.Opener(["not bytes"], None)


def test_the_bus_takes_the_cpp_ones_when_built_and_pythons_otherwise(monkeypatch):
    assert isinstance(auth.bus_sealer(KEY, "skills"), skillbus_native.Sealer)
    assert isinstance(auth.bus_opener([KEY], Policy.parse(POLICY)), auth.NativeOpener)
    assert isinstance(auth.bus_opener([KEY], lambda i, c: True), auth.Opener)  # (a rule only Python can run)
    with pytest.raises(ValueError, match="1 to 255 bytes"):
        auth.bus_sealer(KEY, "x" * 300)  # named as Python's Sealer names it
    monkeypatch.setenv(native.ENV, "0")
    assert isinstance(auth.bus_sealer(KEY, "skills"), auth.Sealer)
    assert isinstance(auth.bus_opener([KEY]), auth.Opener)
