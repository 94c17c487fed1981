"""The operator's commands against a launched system, under the system's own bus policy
(deploy/policy.conf, which `skillbus launch` passes to every program), where most tests'
sandbox bus has no policy at all: what a command sends, the policy lets an operator send.

Seen: `skillbus tree ClearTable` asked the skill process on its own RPC area, which the
policy keeps for the manager (it ticks skills there); the process dropped every attempt
("dropped forbidden: operator may not send on SB_SKPROC_SKILLS_REQ") and the command
printed "cannot expand: ... no reply within 30.0 s" after half a minute.
"""

from __future__ import annotations

from skillbus.waiting import wait_until
from test_launch_run_dir import box, skillbus_in, wait_no_procs  # noqa: F401 (box: a fixture)

LAUNCH = ["launch", "--wall-clock", "--no-task", "--run-dir", "robot"]


def test_operator_commands_are_allowed_by_the_systems_policy(box, tmp_path):  # noqa: F811
    rc, out, err = skillbus_in(box, tmp_path, *LAUNCH, timeout=120)
    assert rc == 0, out + err
    try:
        # (launch returns once every program runs; the skill process registers a moment later)
        wait_until(lambda: "ClearTable" in skillbus_in(box, tmp_path, "skills", timeout=60)[1], 60,
                   "the skill process registered")
        rc, out, err = skillbus_in(box, tmp_path, "tree", "ClearTable", timeout=60)
        assert rc == 0 and "cannot expand" not in out, out + err
        lines = out.splitlines()
        assert lines[0].startswith("ClearTable ["), out
        assert sum(1 for line in lines if line.strip().startswith("Grasp")) == 3, out  # (three cubes)
        for command in (["skills"], ["wm", "tree"], ["sim", "status"], ["tree", "Pick", "-p", "Object=skiros:Cube-2"],
                        ["run", "GripperOpen", "--timeout", "30"]):
            rc, out, err = skillbus_in(box, tmp_path, *command, timeout=60)
            assert rc == 0, (command, out + err)
    finally:
        rc, out, err = skillbus_in(box, tmp_path, "shutdown", "--run-dir", "robot", timeout=60)
        assert rc == 0, out + err
        assert not wait_no_procs(box, 20)
    dropped = {log.name: [line for line in log.read_text(errors="replace").splitlines() if "forbidden" in line]
               for log in (tmp_path / "robot" / "logs").glob("*.err")}
    assert not any(dropped.values()), dropped  # nothing the operator sent was refused
