"""TransferProducts retries a product whose Place failed after its Pick: the product is
still in the gripper, so the retry places it instead of picking it again (a second Pick
fails its NotHolding pre-condition: the fault suite's wall-clock trials saw a release cut
short by a gripper fault end the whole ClearTable that way). Real world model, manager
and skill process; Pick and Place are primitives that move only containment
(skill_libs/transfer_skills.py)."""

import sys

from skillbus import paths
from test_skills import LIBS, cli, mgr_binary


def test_a_product_left_in_the_gripper_by_a_failed_place_is_placed_by_the_retry(sandbox, tmp_path):
    sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", str(tmp_path / "wm"),
                         "--scene", str(paths.demo_scene().with_suffix("").with_suffix(".ttl"))])
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    proc = sandbox.start("proc1", [sys.executable, "-m", "skillbus.cli", "skills-process", "--name", "proc1",
                                   "--library", "transfer_skills", "--world-model"], env={"PYTHONPATH": str(LIBS)})
    proc.wait_for("registered", 60)
    rc, out, err = cli(sandbox, "run", "TransferProducts", "-p", "Gripper=skiros:Gripper-7", "-p", "Arm=skiros:Arm-8",
                       "-p", "From=skiros:Table-1", "-p", "To=skiros:Bin-5", "--timeout", "60", timeout=90)
    assert rc == 0, out + err
    assert "Success" in out.splitlines()[-1], out
    # the first product: Pick, the failed Place, then on the retry only a Place
    first = out[out.index("(RetryOnFail(1)) Success: succeeded at attempt 2"):].splitlines()
    assert [line.strip() for line in first[1:6]] == [
        "(SelectorStar) Success: Place succeeded", "Place Success: placed (world model only)",
        "(SerialStar) Idle", "Pick Idle", "Place Idle"], out
    rc, tree, err = cli(sandbox, "wm", "tree")
    assert rc == 0, err
    bin_part = tree[tree.index("Bin-5"):]
    assert sum(1 for line in bin_part.splitlines() if "Cube" in line) == 3, tree
