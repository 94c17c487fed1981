"""The world model's data directory against damage, missing files, crashes and power
losses, through the real wm_server and the Python client.

Corruption (a bit flip in record 0, 150 or the last of 300, a huge length field) stops
the start with one line naming the file, the offset and the records; the file is left
byte for byte as it was; `skillbus wm repair` keeps the records before the damage (the
original aside as journal.bin.corrupt), and the server then starts with exactly the
acknowledged writes before the damage. A missing journal or snapshot is named. A torn
tail is cut with a warning naming its offset. kill -9 and simulated power losses at
random points of a write sequence lose no acknowledged write and never stop the start
(journal_fault_driver.py, with the fsync shim tests/support/fsync_shim.c):
SKILLBUS_FAULT_POINTS points (50 here; `make faults` runs 1,000)."""

from __future__ import annotations

import hashlib
import json
import os
import random
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import TESTS, last_json, python_tool
from support.skip_policy import cannot_run
from skillbus import paths

SCENE = TESTS.parent / "deploy" / "scenes" / "demo.ttl"
POINTS = int(os.environ.get("SKILLBUS_FAULT_POINTS", "50"))
HEADER, FRAME = 20, 12  # the journal's header and each record's frames (wm_server/include/skillbus/wm/journal.hpp)


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def record_offsets(journal: Path) -> list[int]:
    b = journal.read_bytes()
    pos, out = HEADER, []
    while pos + FRAME <= len(b):
        out.append(pos)
        pos += 2 * FRAME + int.from_bytes(b[pos:pos + 4], "little")
    assert pos == len(b), "the journal does not end with a whole record"
    return out


def start_server(sandbox, data: Path, name: str):
    return sandbox.start(name, [paths.binary("wm_server"), "--wall-clock", "--data", data, "--scene", SCENE,
                                "--name", name])


def write(sandbox, data: Path, n: int) -> None:
    """n acknowledged writes (labels w0..w<n-1>) after the scene (version 1), then a clean stop."""
    server = start_server(sandbox, data, "wm-writes")
    writer = sandbox.start("writer", python_tool("wm_scenarios.py", "writer", str(n)))
    assert sandbox.wait(writer, 120) == 0, writer.stderr()[-2000:]
    assert writer.stdout().count("ack ") == n
    sandbox.kill(server, signal.SIGTERM)
    assert sandbox.wait(server, 20) == 0, server.stderr()[-2000:]


def world(sandbox, data: Path, name: str) -> dict:
    """Starts the server on `data` and reads its world through the Python client: the
    version and how often each w-label is there."""
    start_server(sandbox, data, name)
    code = ("import json, collections; from skillbus.bus import open_bus; "
            "from skillbus.world import WorldModelInterface; w = WorldModelInterface(open_bus(), 'probe', timeout=20); "
            "print(json.dumps({'version': w.version, 'labels': collections.Counter("
            "e.label for e in w.get_elements() if e.label.startswith('w'))}))")
    p = sandbox.start(f"probe-{name}", [sys.executable, "-c", code])
    assert sandbox.wait(p, 60) == 0, p.stderr()[-2000:]
    return last_json(p.stdout())


def refused(sandbox, data: Path, name: str) -> str:
    """Starts the server on `data`: it must refuse, with exit code 2 and one line."""
    p = start_server(sandbox, data, name)
    assert sandbox.wait(p, 30) == 2, p.stderr()[-2000:]
    lines = p.stderr().strip().splitlines()
    assert len(lines) == 1, p.stderr()
    assert lines[0].startswith("wm_server: cannot start: "), lines[0]
    return lines[0]


def skillbus(sandbox, name: str, *args) -> tuple[int, str, str]:
    p = sandbox.start(name, [sys.executable, "-m", "skillbus.cli", *map(str, args)])
    rc = sandbox.wait(p, 60)
    return rc, p.stdout(), p.stderr()


def flip_in_body(record: int):
    def damage(b: bytearray, offsets: list[int]) -> tuple[int, int]:
        i = offsets[record]
        b[i + FRAME + 17] ^= 0x08
        return i, record
    return damage


def huge_length(b: bytearray, offsets: list[int]) -> tuple[int, int]:
    i = offsets[150]
    b[i + 3] = 0x7F  # the length's top byte: 2 GB
    return i, 150


@pytest.mark.parametrize("damage", [flip_in_body(0), flip_in_body(150), flip_in_body(299), huge_length],
                         ids=["bit-flip-record-0", "bit-flip-record-150", "bit-flip-last-record", "huge-length"])
def test_corruption_stops_the_start_and_repair_keeps_the_acknowledged_records_before_it(sandbox, tmp_path, damage):
    data = tmp_path / "data"
    write(sandbox, data, 300)
    journal = data / "journal.bin"
    b = bytearray(journal.read_bytes())
    at, record = damage(b, record_offsets(journal))
    journal.write_bytes(b)
    before = sha256(journal)

    line = refused(sandbox, data, "wm-refused")
    assert f"{journal} is corrupt at byte {at}: record {record} " in line, line
    assert (f"the {record} records before it (versions 2-{record + 1}) are intact" if record
            else "no record before it is intact (the world stays at version 1)") in line, line
    assert f"skillbus wm repair --data {data}" in line, line
    assert sha256(journal) == before  # the evidence is kept
    assert sorted(os.listdir(data)) == ["journal.bin", "lock", "snapshot.bin"]

    rc, out, err = skillbus(sandbox, "repair", "wm", "repair", "--data", data)
    assert rc == 0, err
    assert f"was corrupt at byte {at}" in out, out
    assert (f"kept the {record} intact records before it" if record else "kept no record") in out, out
    assert f"the original is kept unchanged as {journal}.corrupt" in out, out
    assert sha256(data / "journal.bin.corrupt") == before
    assert journal.read_bytes() == b[:at]  # the header and the records before the damage

    w = world(sandbox, data, "wm-repaired")
    assert w["labels"] == {f"w{i}": 1 for i in range(record)}
    assert w["version"] == 1 + record


def test_a_missing_journal_or_snapshot_is_named_and_the_files_are_kept(sandbox, tmp_path):
    data = tmp_path / "data"
    write(sandbox, data, 20)
    journal, snapshot = data / "journal.bin", data / "snapshot.bin"
    hashes = {journal: sha256(journal), snapshot: sha256(snapshot)}

    snapshot.rename(tmp_path / "snapshot.bin")
    line = refused(sandbox, data, "wm-no-snapshot")
    assert f"{snapshot} is missing, but {journal} goes on from the snapshot at version 1" in line, line
    rc, _, err = skillbus(sandbox, "repair-no-snapshot", "wm", "repair", "--data", data)
    assert rc == 1 and f"cannot repair: {snapshot} is missing" in err, err
    (tmp_path / "snapshot.bin").rename(snapshot)

    journal.rename(tmp_path / "journal.bin")
    line = refused(sandbox, data, "wm-no-journal")
    assert f"{journal} is missing, but {snapshot} (version 1) is there: the commits after version 1 would be lost" \
        in line, line
    assert not journal.exists()
    (tmp_path / "journal.bin").rename(journal)
    assert {p: sha256(p) for p in hashes} == hashes

    w = world(sandbox, data, "wm-whole")
    assert w["labels"] == {f"w{i}": 1 for i in range(20)} and w["version"] == 21


def test_repair_of_a_missing_journal_goes_on_from_the_snapshot(sandbox, tmp_path):
    data = tmp_path / "data"
    write(sandbox, data, 5)
    (data / "journal.bin").unlink()
    rc, out, err = skillbus(sandbox, "repair", "wm", "repair", "--data", data)
    assert rc == 0 and "wrote an empty journal going on from version 1" in out, (out, err)
    w = world(sandbox, data, "wm-from-snapshot")
    assert w == {"version": 1, "labels": {}}  # a person chose to go on without the 5 writes


def test_a_torn_tail_is_cut_with_a_warning_naming_its_offset(sandbox, tmp_path):
    data = tmp_path / "data"
    write(sandbox, data, 20)
    journal = data / "journal.bin"
    whole = journal.read_bytes()
    last = record_offsets(journal)[-1]
    journal.write_bytes(whole + whole[last:last + 40])  # a write cut short by a crash
    w = world(sandbox, data, "wm-torn")
    assert w["labels"] == {f"w{i}": 1 for i in range(20)} and w["version"] == 21
    log = (sandbox.log_dir / "wm-torn.err").read_text()
    assert f"[warn] wm_journal: cut off a torn record at byte {len(whole)} of {journal} (40 bytes" in log, log
    assert journal.read_bytes() == whole


@pytest.fixture(scope="session")
def fsync_shim(tmp_path_factory) -> Path:
    cc = shutil.which("cc") or shutil.which("gcc")
    if not cc:
        cannot_run("no C compiler (cc) to build tests/support/fsync_shim.c")
    out = tmp_path_factory.mktemp("shim") / "fsync_shim.so"
    subprocess.run([cc, "-shared", "-fPIC", "-O2", "-Wall", "-o", str(out), str(TESTS / "support" / "fsync_shim.c"),
                    "-ldl"], check=True, capture_output=True, text=True)
    return out


@pytest.mark.timeout(300 + POINTS)
def test_kill_9_and_power_loss_at_random_points_lose_no_acknowledged_write(sandbox, tmp_path, fsync_shim):
    seed = random.randrange(1 << 31)  # in the failure message: the run can be repeated
    driver = sandbox.start("faults", python_tool("journal_fault_driver.py", "--points", str(POINTS), "--seed",
                                                 str(seed), "--work", str(tmp_path / "work"),
                                                 "--shim", str(fsync_shim)))
    rc = sandbox.wait(driver, 200 + POINTS)
    r = last_json(driver.stdout())
    assert rc == 0 and r["ok"], f"seed {seed}: {r['failures']}\n{driver.stderr()[-3000:]}"
    assert r["points"] == POINTS and r["server_starts"] == POINTS + 1
    assert r["survivors"] == r["acknowledged"] == r["version"] > 0
    assert set(r["modes"]) == {"kill", "power-synced", "power-prefix", "power-zeros"}, r["modes"]
    print(f"\njournal faults (seed {seed}): {json.dumps(r)}")
