"""A core of its own for the physics server under lockstep (`skillbus demo --physics-core`).

Under lockstep the physics server steps while the participants work on the frame
(`sim_server --pipeline`), and a frame ends when both are done. On a machine with few
cores the participants, woken by every frame's clock, were scheduled onto the physics'
core too and preempted its step: on 2 cores the step took 0.76 ms a frame in the demo
against 0.70 ms with the other processes kept off its core, and the demo ran 7-11 %
faster (docs/benchmarks.md). So the demo gives the physics server one core and every
other program the others, with `taskset` in front of each command (visible in the run
folder's supervisord.conf).

The other programs also run under the batch scheduling policy (``chrt --batch 0``): woken
together by every clock on their shared core, each used to preempt the one running (0.7
involuntary switches a frame for the skill process, as many for the gripper device), and
each switch costs its time on a virtual machine. Under SCHED_BATCH a woken program waits
for the running one to block, so each does its frame's work in one go: 0.06 involuntary
switches a frame, the demo 1-2 % faster (docs/benchmarks.md). Without `chrt` (util-linux)
the placement goes on without it, and says so.

On its own core the physics server also polls for the frame's acks once its step is done
(``sim_server --ack-poll-us``) instead of sleeping until one comes: nothing else needs that
core, and on a virtual machine a sleeping receiver on another core costs each sender about
30 µs to wake (a vCPU's wake-up goes through the host) and costs the sleeper as long
again before it runs. The participants' acks are sent from their core, where the demo's
CPU is short.

While the session runs the physics server also holds a CPU latency request of 0 µs
(``sim_server --cpu-latency-us 0``, Linux PM QoS): idle cores poll instead of halting, so
the clock and state that wake the participants each frame need no interrupt through the
host (a round trip between the two cores 150 -> 35 µs on this VM; the demo's frames about
6 % shorter, the physics alone unchanged: docs/benchmarks.md). The kernel drops the request
when the server ends. It costs power while held: the idle cores spin. The device
(/dev/cpu_dma_latency) is root's; when this process cannot write it, the placement goes on
without the request, and says so.

It is a trade: a physics server held to one core cannot move when something else, outside
the system, takes that core. `--physics-core off` leaves placement to the kernel;
`--physics-core N` names the core. With one usable core there is nothing to split, and
`auto` changes nothing.
"""

from __future__ import annotations

import dataclasses
import os
import shutil

from skillbus.system import Program

PHYSICS = "sim"  # the program that steps the physics (skillbus.system)
# How long the physics server on its own core polls for a frame's acks after its step before
# it sleeps: longer than a frame's acks take past the step but for a motion plan's frames.
ACK_POLL_US = 2000
# Where a CPU latency request is made (skillbus/apps/cpu_latency.hpp).
CPU_LATENCY_DEVICE = "/dev/cpu_dma_latency"


class LayoutError(ValueError):
    """A core that cannot be used, named with the ones that can."""


def cpu_list(cpus: set[int] | list[int]) -> str:
    """taskset's form: 0,2,3."""
    return ",".join(str(c) for c in sorted(cpus))


@dataclasses.dataclass
class Layout:
    programs: list[Program]
    note: str                      # where each went, or why nothing changed
    others: set[int] | None = None  # the cores of everything but the physics (None: unchanged)
    physics_options: list[str] = dataclasses.field(default_factory=list)  # appended to the physics server's argv


def place(progs: list[Program], choice: str = "auto", allowed: set[int] | None = None,
          taskset: str | None = None, chrt: str | None = None,
          latency_device: str = CPU_LATENCY_DEVICE) -> Layout:
    """The programs with the physics server on a core of its own and the rest on the other
    cores this process may use (`allowed`, default its own affinity), under the batch
    policy (`chrt`: the tool's path, default found on PATH), with idle cores polling while
    the physics server runs if this process may write `latency_device`. `choice`: "auto"
    (the last usable core), "off", or a core's number."""
    allowed = set(allowed if allowed is not None else os.sched_getaffinity(0))
    choice = choice.strip().lower()
    if choice == "off":
        return Layout(progs, "placement left to the kernel (--physics-core off)")
    if choice == "auto":
        core = max(allowed)
    else:
        try:
            core = int(choice)
        except ValueError:
            raise LayoutError(f"--physics-core {choice!r}: 'auto', 'off' or a core's number "
                              f"(this process may use {cpu_list(allowed)})") from None
        if core not in allowed:
            raise LayoutError(f"--physics-core {core}: not a core this process may use ({cpu_list(allowed)})")
    others = allowed - {core}
    if not others:
        if choice == "auto":
            return Layout(progs, f"one usable core ({core}): the physics server shares it")
        raise LayoutError(f"--physics-core {core}: the only core this process may use; the other programs need "
                          f"one too (give --physics-core off)")
    if not any(p.name == PHYSICS for p in progs):
        return Layout(progs, "no physics server among the programs")
    tool = taskset or shutil.which("taskset")
    if tool is None:
        if choice == "auto":
            return Layout(progs, "taskset (util-linux) is not installed: placement left to the kernel")
        raise LayoutError(f"--physics-core {core}: taskset (util-linux) is not installed")
    batch_tool = chrt or shutil.which("chrt")
    batch = [batch_tool, "--batch", "0"] if batch_tool else []
    physics_options = ["--ack-poll-us", str(ACK_POLL_US)]
    if os.access(latency_device, os.W_OK):
        physics_options += ["--cpu-latency-us", "0"]
        idle = "idle cores polling"
    elif os.path.exists(latency_device):
        idle = f"idle cores halting: {latency_device} is not writable by this user (root's by default)"
    else:
        idle = f"idle cores halting: no {latency_device} here"
    out = [dataclasses.replace(p, argv=[tool, "--cpu-list", cpu_list({core}), *p.argv, *physics_options])
           if p.name == PHYSICS else
           dataclasses.replace(p, argv=[tool, "--cpu-list", cpu_list(others), *batch, *p.argv])
           for p in progs]
    how = "batch scheduling" if batch else "no batch scheduling: chrt (util-linux) is not installed"
    return Layout(out, f"the physics server on core {core} (polling for acks; {idle}), the other programs on "
                       f"{cpu_list(others)} ({how})", others, physics_options)
