"""The per-frame codecs of the Python participants, each beside the code it replaced, in
the same run (in-process loops; no bus):

- the physics' state as the gripper device reads it every frame its fingers move or hold
  (skillbus.sim.state_decode) against LCM's generated decoder (skillbus.msgs.decode);
- the lockstep clock every Python participant reads in each frame it works in
  (skillbus_native.decode_clock) against Python's decoder (lockstep_wire.python_decode_clock);
- a tick reply's parameters, as the skill process writes them at every tick
  (skillbus_native.params_wire) against Python's (tick_wire.param_bytes), for parameters
  like the demo's: three element parameters that are reader copies of the replica's
  elements, an element default and a number.

The demo's own figures (what these take inside its frames) are in docs/benchmarks.md,
"Pick and place". No targets: the issue's targets are the demo's (bench/pick_and_place.py).

Run: .venv/bin/python bench/frame_codecs.py   (in `make bench`)
"""

from __future__ import annotations

import statistics
import sys
import time
from typing import Callable

from skillbus import native
from skillbus.lockstep_wire import decode_clock, python_decode_clock
from skillbus.msgs import channel_count_t, decode, header_t, lockstep_clock_t, sim_contact_t, sim_object_t, sim_state_t
from skillbus.sim.state_decode import decode_sim_state
from skillbus.skill.param import Param, ParamTypes
from skillbus.skill.tick_wire import param_bytes
from skillbus.world.element import Element

LOOPS, ROUNDS = 5000, 5


def per_call_us(fn: Callable[[], object]) -> float:
    """The median over ROUNDS of LOOPS calls, µs a call."""
    fn()
    times = []
    for _ in range(ROUNDS):
        t0 = time.perf_counter()
        for _ in range(LOOPS):
            fn()
        times.append((time.perf_counter() - t0) / LOOPS * 1e6)
    return statistics.median(times)


def demo_like_state() -> bytes:
    """A sim_state_t shaped as the demo's: an arm of six joints and two fingers, three
    cubes, the fingers touching one."""
    s = sim_state_t()
    s.header.frame, s.header.sim_time_ns, s.header.sender, s.header.seq = 812, 16_240_000_000, "sim", 3
    s.joint_names = [f"ur5e/joint_{i}" for i in range(6)] + ["finger_left_joint", "finger_right_joint"]
    s.num_joints = len(s.joint_names)
    s.position, s.velocity, s.effort = ([0.1 * i for i in range(8)] for _ in range(3))
    s.tool_pose = [0.4, 0.1, 0.3, 0.0, 1.0, 0.0, 0.0]
    s.finger_width, s.finger_force, s.finger_width_target = 0.0412, 19.7, 0.0
    s.arm_command_id, s.arm_moving, s.arm_tracking_error = "skills-move_arm-17", True, 0.002
    for i in range(3):
        o = sim_object_t()
        o.name, o.pose, o.twist = f"cube_{i}", [0.1 * i, 0.2, 0.05, 0.0, 0.0, 0.0, 1.0], [0.0] * 6
        s.objects.append(o)
    s.num_objects = 3
    for side in ("left", "right"):
        c = sim_contact_t()
        c.body_a, c.body_b, c.points, c.normal_force = f"finger_{side}", "cube_0", 4, 9.5
        s.contacts.append(c)
    s.num_contacts = 2
    return s.encode()


def demo_like_clock() -> bytes:
    """A lockstep_clock_t with the demo's four participants and ten counts."""
    c = lockstep_clock_t()
    c.header.frame, c.header.sim_time_ns, c.header.sender = 812, 16_240_000_000, "sim"
    c.frame_period_ns = 20_000_000
    c.participants = ["gripper", "skill_mgr", "skills", "wm"]
    c.num_participants = 4
    channels = ["SB_SIM_STATE", "SB_ROBOT_ARM_STATE", "SB_SIM_CONTACTS", "SB_CAN_SYNC", "SB_RPC_SKPROC_SKILLS_REQ",
                "SB_RPC_SKPROC_SKILLS_REP", "SB_SKILL_PROGRESS", "SB_WM_CHANGES", "SB_SIM_GRIPPER_CMD", "SB_ROBOT_ARM_CMD"]
    for i, ch in enumerate(channels):
        n = channel_count_t()
        n.sender, n.channel, n.frame, n.count = ["sim", "skills", "skill_mgr", "gripper"][i % 4], ch, 811, 1
        c.counts.append(n)
    c.num_counts = len(c.counts)
    return c.encode()


def demo_like_params() -> list[Param]:
    """Three element parameters holding reader copies of the replica's elements (a cube,
    the gripper, the arm), an element parameter at its default, and a number."""
    params = []
    for key, concept, label, props in (("Object", "skiros:Product", "cube_0", 9), ("Gripper", "skiros:Gripper",
                                                                                     "gripper", 6),
                                       ("Arm", "skiros:Manipulator", "ur5e", 6)):
        src = Element(concept, label, f"{concept}-{len(params) + 1}")
        for k in range(props):
            src.setProperty(f"skiros:P{k}", [0.1 * k, 0.2, 0.3] if k % 3 == 0 else f"value-{k}")
        p = Param(key, f"the {key.lower()}", Element(concept), ParamTypes.Required)
        p.setValues([Element._reader_copy(src, ())])
        params.append(p)
    params.append(Param("Location", "where to", Element("skiros:Location"), ParamTypes.Optional))
    params.append(Param("Speed", "of the arm, 0-1", 0.5, ParamTypes.Optional))
    return params


def main() -> int:
    lib = native.module()
    if lib is None or decode_clock is python_decode_clock:
        print("skillbus_native is not built or is switched off (SKILLBUS_NATIVE=0): run `make build`")
        return 1
    state, clock, params = demo_like_state(), demo_like_clock(), demo_like_params()
    assert decode_sim_state(state).encode() == state and decode_clock(clock).encode() == clock
    assert lib.params_wire(params) == b"".join(param_bytes(p) for p in params)
    rows = [
        ("the physics' state (8 joints, 3 objects, 2 contacts)", lambda: decode_sim_state(state),
         lambda: decode(sim_state_t, state), "LCM's generated decoder"),
        ("the lockstep clock (4 participants, 10 counts)", lambda: decode_clock(clock),
         lambda: python_decode_clock(clock), "Python's decoder"),
        ("a tick reply's 5 parameters (3 reader copies)", lambda: lib.params_wire(params),
         lambda: b"".join([param_bytes(p) for p in params]), "Python's param_bytes"),
    ]
    print(f"per-frame codecs of the Python participants, µs a call (medians of {ROUNDS} rounds of {LOOPS})")
    for what, ours, peer, peer_name in rows:
        a, b = per_call_us(ours), per_call_us(peer)
        print(f"    {what:55s} {a:7.2f}   {peer_name} {b:7.2f}   {b / a:5.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
