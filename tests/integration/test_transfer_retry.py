"""TransferProducts retries a product whose Place failed after its Pick: the product is
still in the gripper, so the retry places it instead of picking it again (a second Pick
fails its NotHolding pre-condition: the fault suite's wall-clock trials saw a release cut
short by a gripper fault end the whole ClearTable that way). Real world model, manager
and skill process; Pick and Place are primitives that move only containment
(skill_libs/transfer_skills.py)."""

from test_skills import cli, start_system, start_wm


def test_a_product_left_in_the_gripper_by_a_failed_place_is_placed_by_the_retry(sandbox, tmp_path):
    start_wm(sandbox, tmp_path / "wm")
    start_system(sandbox, "transfer_skills", world_model=True, timeout=60)
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
