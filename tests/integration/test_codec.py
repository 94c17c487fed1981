"""Cross-language codec: every message type published from C++ is decoded in Python, and
the other way round, over real LCM between real processes."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from codec_samples import samples  # noqa: E402

from conftest import last_json  # noqa: E402


def codec_peer(binary):
    return binary("codec_peer")


def test_cpp_to_python_every_type(sandbox, binary):
    want = samples()
    sandbox.start("codec_peer", [codec_peer(binary), "--publish", "20"])
    # The test process is outside the namespace: a Python peer inside decodes and judges.
    peer = sandbox.start("py_receiver", [sys.executable, str(Path(__file__).parent / "codec_py_peer.py"),
                                         "--check", "15", *want])
    sandbox.wait(peer, 30)
    got = last_json(peer.stdout())
    for name in want:
        assert got[name] == "ok", f"{name}: {got[name]}"


def test_python_to_cpp_every_type(sandbox, binary):
    checker = sandbox.start("codec_peer", [codec_peer(binary), "--check", "15"])
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
