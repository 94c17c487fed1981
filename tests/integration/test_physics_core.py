"""The demo's placement (skillbus.cpu_layout) on real processes: the physics server runs on
its core only, the other programs on the others under the batch policy (the kernel's own
view of each process)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from skillbus.cpu_layout import place
from skillbus.system import programs
from skillbus.waiting import wait_until


def cores_of(pid: int) -> str:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Cpus_allowed_list:"):
            return line.split()[1]
    raise AssertionError(f"no Cpus_allowed_list for {pid}")


@pytest.mark.allow_skip
@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one usable core: nothing to split")
def test_the_physics_server_runs_on_its_core_and_the_rest_on_the_others(sandbox, tmp_path):
    allowed = sorted(os.sched_getaffinity(0))
    layout = place(programs(tmp_path / "run"), "auto")
    by_name = {p.name: p for p in layout.programs}
    procs = {n: sandbox.start(n, by_name[n].argv) for n in ("sim", "wm")}
    for n, comm in (("sim", "sim_server"), ("wm", "wm_server")):
        pid = procs[n].popen.pid
        wait_until(lambda: Path(f"/proc/{pid}/comm").read_text().strip() == comm, 20, f"{comm} started",
                   interval=0.05)
    assert cores_of(procs["sim"].popen.pid) == str(allowed[-1])
    others = allowed[:-1]
    want = str(others[0]) if len(others) == 1 else None
    got = cores_of(procs["wm"].popen.pid)
    assert got == want if want else str(allowed[-1]) not in got.replace("-", ",").split(","), got
    # The others under the batch policy (a woken one does not preempt the running one);
    # the physics server under the normal one.
    assert os.sched_getscheduler(procs["wm"].popen.pid) == os.SCHED_BATCH
    assert os.sched_getscheduler(procs["sim"].popen.pid) == os.SCHED_OTHER
