"""A sender that keeps sending what a server refuses must not fill its log: the world
model server on the wall clock, flooded with 3,000 signed SB_WM_TXN messages that do not
decode, logs the first few and then one line per thousand (with the count), and goes on
serving (issue 14: logs rate-limit repeated errors per sender)."""

import re
import sys

from conftest import python_tool
from skillbus import paths


def test_a_flood_of_refused_transactions_leaves_a_few_log_lines(sandbox, tmp_path):
    wm = sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", str(tmp_path / "wm"), "--scene",
                              str(paths.demo_scene().with_suffix("").with_suffix(".ttl"))])
    wm.wait_for("serving", 30)
    flood = sandbox.start("flood", python_tool("txn_flood.py", "3000"))
    assert sandbox.wait(flood, 60) == 0, flood.stderr()
    tree = sandbox.start("tree", [sys.executable, "-m", "skillbus.cli", "wm", "tree"])
    assert sandbox.wait(tree, 30) == 0 and "Cube" in tree.stdout(), tree.stderr()  # it goes on serving
    lines = [line for line in wm.stderr().splitlines() if "SB_WM_TXN" in line]
    counts = [int(n) for line in lines for n in re.findall(r"#(\d+)", line)]
    assert counts and max(counts) >= 2000, lines  # the refusals were counted ...
    assert len(lines) <= 10, "\n".join(lines)     # ... and logged a few times, not 3,000
    assert wm.returncode is None
