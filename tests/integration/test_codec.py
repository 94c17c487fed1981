"""Cross-language and cross-transport codec: every message type (a sample of each, every
field set, generated from lcmtypes/ by codec_samples.py for both sides) published from C++
is decoded in Python, and the other way round, between real processes over each transport
(LCM's udpm://, and Cyclone DDS: Debian's 0.10 in C++, the wheel's 11 in Python)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from codec_samples import VALUES, fields, samples, type_names  # noqa: E402

from conftest import last_json  # noqa: E402
from skillbus import paths  # noqa: E402


def test_every_type_of_lcmtypes_has_a_sample_with_every_field_set():
    lcm_files = sorted(p.stem for p in (paths.REPO_ROOT / "lcmtypes").glob("*.lcm"))
    assert type_names() == lcm_files
    kinds = set()

    def walk(msg):
        for slot, typename, dims in fields(type(msg)):
            value = getattr(msg, slot)
            for _ in dims:  # down to one element (every array is 1 to 3 long)
                assert len(value) >= 1, (type(msg).__name__, slot)
                value = value[0]
            kinds.add(typename if typename in VALUES else "struct")
            if typename not in VALUES:
                walk(value)

    for name, msg in samples().items():
        walk(msg)
    assert kinds == set(VALUES) | {"struct"}  # every primitive type of LCM, and nesting


def test_cpp_to_python_every_type(transport_sandbox, binary):
    sandbox = transport_sandbox
    want = samples()
    sandbox.start("codec_peer", [binary("codec_peer"), "--publish", "20"])
    # The test process is outside the namespace: a Python peer inside decodes and judges.
    peer = sandbox.start("py_receiver", [sys.executable, str(Path(__file__).parent / "codec_py_peer.py"),
                                         "--check", "15", *want])
    sandbox.wait(peer, 30)
    got = last_json(peer.stdout())
    assert set(got) == set(want)
    bad = {name: got[name] for name in want if got[name] != "ok"}
    assert not bad, bad


def test_python_to_cpp_every_type(transport_sandbox, binary):
    sandbox = transport_sandbox
    checker = sandbox.start("codec_peer", [binary("codec_peer"), "--check", "15"])
    sandbox.start("py_publisher", [sys.executable, str(Path(__file__).parent / "codec_py_peer.py"),
                                   "--publish", "20"])
    assert sandbox.wait(checker, 30) == 0, checker.stdout() + checker.stderr()
    verdict = last_json(checker.stdout())
    assert set(verdict) == set(samples())
    assert all(v == "ok" for v in verdict.values()), verdict


def test_python_reencodes_what_it_decodes_byte_for_byte():
    # Re-encoding what Python decodes reproduces the bytes: no field is lost or reordered.
    for name, msg in samples().items():
        data = msg.encode()
        assert type(msg).decode(data).encode() == data, name
