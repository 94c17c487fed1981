"""Holding a task before a test acts on it while it runs (docs/testing.md, "Waiting").

Under lockstep a ClearTable is over in seconds; a test that saw it running and then
signals, stops or pauses it can act after it ended on a loaded machine. `HOLD_TASK`, run
in the system's sandbox as `python -c HOLD_TASK N`, pauses task N over RPC as soon as
the manager runs it (retried every 10 ms in one process: a CLI per try takes a second
to start) and prints "held"."""

HOLD_TASK = """
import sys
from skillbus.bus import open_bus
from skillbus.msgs import skill_start_t, skill_task_t
from skillbus.rpc import RpcClient, RpcError
from skillbus.waiting import wait_until
client, req = RpcClient(open_bus(), "SKILL", "hold"), skill_start_t()
req.task = int(sys.argv[1])
# (RpcError, retried: no manager yet or no such task yet; a queued task is paused too)
wait_until(lambda: client.call("pause", req, skill_task_t, timeout=0.5), 120, f"task {req.task} paused",
           interval=0.01, retry_on=(RpcError,))
print("held", flush=True)
"""


def hold_task(sandbox, task: int = 1):
    """Starts the holder of `task` in `sandbox`; returns its process (wait for "held")."""
    import sys
    return sandbox.start(f"hold-{task}-{len(sandbox.procs)}", [sys.executable, "-c", HOLD_TASK, str(task)])
