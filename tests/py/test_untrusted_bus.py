"""Untrusted input from the bus (docs/transport.md, "Untrusted input"): every Python
receiver that acts on a message's values drops one whose values are not finite, out of
range, of the wrong length or of an unknown kind, counts it and keeps what it had: the
arm's and the camera's drivers' messages, the world model's change stream and
transaction results, the lockstep clock and stamps, a skill process's ticks and
expansions, the physics script player's states. The gripper's side:
test_untrusted_can.py."""

from __future__ import annotations

import math

import pytest

from skillbus.bus import open_bus
from skillbus.lockstep import LockstepParticipant, Stamp, StampedMessage, peek_stamp
from skillbus.msgs import (channel_count_t, header_t, lockstep_clock_t, robot_arm_state_t, robot_object_t,
                           robot_objects_t, sim_state_t, skill_param_t, skill_tick_t, skill_value_t, wm_change_t,
                           wm_commit_t, wm_element_t, wm_op_t, wm_property_t, wm_relation_t, wm_value_t)
from skillbus.robot.arm import Arm
from skillbus.robot.camera import Camera, CameraError
from skillbus.sim.script import ScriptPlayer
from skillbus.skill import ParamTypes, PrimitiveBase, SerialStar, SkillBase, SkillDescription
from skillbus.skill.process import SkillProcess
from skillbus.skill.skill import State
from skillbus.validate import kind_of
from skillbus.world.client import WorldModelInterface

NOT_FINITE = [math.nan, math.inf, -math.inf]
UNIT = [0.0, 0.0, 0.0, 1.0]  # the identity rotation


def wire(msg):
    """`msg` as a receiver gets it: encoded and decoded (NaN and infinities survive)."""
    return type(msg).decode(msg.encode())


# -- the arm's driver (SB_ROBOT_ARM_STATE) ----------------------------------------------------------

def arm_state(**change) -> robot_arm_state_t:
    s = robot_arm_state_t()
    s.joint_names = ["joint1", "joint2"]
    s.num_joints = 2
    s.position, s.velocity, s.effort = [0.1, -0.2], [0.0, 0.0], [1.0, -1.0]
    s.tool_pose = [0.3, 0.0, 0.5] + UNIT
    s.arm_command_id, s.arm_moving, s.arm_tracking_error = "up", False, 0.001
    for k, v in change.items():
        setattr(s, k, v)
    return s


FORGED_ARM = {
    "position[1]": dict(position=[0.1, math.nan]),
    "velocity[0]": dict(velocity=[math.inf, 0.0]),
    "effort[1]": dict(effort=[0.0, -math.inf]),
    "position[0]": dict(position=[1e300, 0.0]),
    "tool_pose[2]": dict(tool_pose=[0.3, 0.0, math.nan] + UNIT),
    "tool_pose.x": dict(tool_pose=[1e9, 0.0, 0.5] + UNIT),
    "tool_pose.rotation": dict(tool_pose=[0.3, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0]),
    "arm_tracking_error": dict(arm_tracking_error=math.nan),
    "num_joints": dict(num_joints=0, joint_names=[], position=[], velocity=[], effort=[]),
    "joint_names": dict(joint_names=["joint1", "joint1"]),
    "joint_names[1]": dict(joint_names=["joint1", ""]),
}


@pytest.mark.parametrize("field", FORGED_ARM)
def test_an_arm_state_with_bad_values_is_counted_and_the_last_good_one_stays(field):
    arm = Arm(open_bus("memq://"))
    arm._on_state(arm_state().encode())
    good = arm.state
    assert good is not None and arm.bad == 0
    arm._on_state(arm_state(**FORGED_ARM[field]).encode())
    assert arm.state is good and arm.joints() == [0.1, -0.2]
    assert arm.bad == 1 and arm.rejects.summary() == {kind_of("SB_ROBOT_ARM_STATE", field): 1}


def test_a_corrupt_state_never_makes_a_move_look_finished():
    arm = Arm(open_bus("memq://"))
    # It claims the trajectory played and settled, with joint positions that are not numbers.
    arm._on_state(arm_state(position=[math.nan, 0.0], arm_command_id="go", arm_moving=False).encode())
    assert arm.finished("go") == (False, "")


# -- the camera's driver (SB_ROBOT_OBJECTS) -----------------------------------------------------------

def objects(*poses, names=None) -> robot_objects_t:
    m = robot_objects_t()
    for i, p in enumerate(poses):
        o = robot_object_t()
        o.name, o.pose, o.support = (names or ["red", "green", "blue"])[i], list(p), "table"
        m.objects.append(o)
    m.num_objects = len(m.objects)
    return m


@pytest.mark.parametrize("pose,names,field", [
    ([0.1, math.nan, 0.0] + UNIT, None, "objects[1].pose[1]"),
    ([0.1, 0.2, -math.inf] + UNIT, None, "objects[1].pose[2]"),
    ([1e12, 0.2, 0.0] + UNIT, None, "objects[1].pose.x"),
    ([0.1, 0.2, 0.0, 0.0, 0.0, 0.0, 5.0], None, "objects[1].pose.rotation"),
    ([0.1, 0.2, 0.0] + UNIT, ["red", ""], "objects[1].name"),
])
def test_detections_with_a_bad_pose_or_no_name_are_counted_and_the_last_good_ones_stay(pose, names, field):
    cam = Camera(open_bus("memq://"))
    with pytest.raises(CameraError):
        cam.objects()
    cam._on(objects([0.1, 0.2, 0.0] + UNIT).encode())
    seen = cam.objects()
    cam._on(objects([0.0, 0.5, 0.1] + UNIT, pose, names=names).encode())
    assert cam.objects() == seen and len(seen) == 1
    assert cam.bad == 1 and cam.rejects.summary() == {kind_of("SB_ROBOT_OBJECTS", field): 1}


# -- the articulated objects' reading (SB_ROBOT_ARTICULATION) ----------------------------------------

def articulation(**bad):
    from skillbus.msgs import articulated_joint_t, articulation_state_t
    j = articulated_joint_t()
    j.object, j.joint, j.concept, j.kind = "cabinet", "drawer_joint", "Drawer", "prismatic"
    j.position, j.velocity, j.lower, j.upper = 0.1, 0.0, 0.0, 0.25
    j.axis, j.origin, j.has_handle, j.handle_pose = [0.0, 1.0, 0.0], [0.1, -0.4, 0.0], True, [0.1, -0.3, 0.3] + UNIT
    for k, v in bad.items():
        setattr(j, k, v)
    m = articulation_state_t()
    m.joints, m.num_joints = [j], 1
    return m


@pytest.mark.parametrize("bad,field", [
    ({"position": math.nan}, "joints[0].position"),
    ({"kind": "telescopic"}, "joints[0].kind"),
    ({"upper": -1.0}, "joints[0].upper"),
    ({"axis": [0.0, 2.0, 0.0]}, "joints[0].axis[1]"),
    ({"handle_pose": [0.1, -0.3, 0.3, 0.0, 0.0, 0.0, 0.0]}, "joints[0].handle_pose.rotation"),
    ({"joint": ""}, "joints[0].joint"),
])
def test_an_articulation_reading_with_bad_values_is_counted_and_the_last_good_one_stays(bad, field):
    from skillbus.robot.articulation import Articulation, ArticulationError
    a = Articulation(open_bus("memq://"))
    with pytest.raises(ArticulationError):
        a.joints()
    a._on(articulation().encode())
    assert a.joints()[0].position == 0.1
    a._on(articulation(**bad).encode())
    assert a.joints()[0].position == 0.1 and a.bad == 1
    assert a.rejects.summary() == {kind_of("SB_ROBOT_ARTICULATION", field): 1}
    a._on(b"\x00" * 7)  # not a message at all
    assert a.joints()[0].position == 0.1 and a.bad == 2  # (decoded when asked)


# -- the world model's change stream (SB_WM_CHANGES) and transaction results --------------------------

@pytest.fixture
def replica(monkeypatch):
    """A world-model client whose replica is at version 3 (no server: resync is stubbed)."""
    monkeypatch.setattr(WorldModelInterface, "resync", lambda self: None)
    wmi = WorldModelInterface(open_bus("memq://"), "test")
    wmi.version = 3
    return wmi


def value(kind=wm_value_t.FLOAT, f=0.5) -> wm_value_t:
    v = wm_value_t()
    v.type, v.f = kind, f
    return v


def element_op(eid="skiros:Cube-2", values=None, kind=wm_op_t.ADD_ELEMENT) -> wm_op_t:
    e = wm_element_t()
    e.id, e.type, e.label = eid, "skiros:Product", "red"
    p = wm_property_t()
    p.key, p.values = "skiros:PositionX", values if values is not None else [value()]
    p.num_values = len(p.values)
    e.properties, e.num_properties = [p], 1
    o = wm_op_t()
    o.kind, o.element, o.relation = kind, e, wm_relation_t()
    return o


def relation_op(s="skiros:Table-1", p="skiros:contain", o="skiros:Cube-2") -> wm_op_t:
    op = wm_op_t()
    op.kind, op.element, op.relation = wm_op_t.ADD_RELATION, wm_element_t(), wm_relation_t()
    op.relation.subject, op.relation.predicate, op.relation.object = s, p, o
    return op


def change(version=4, *ops) -> bytes:
    c = wm_change_t()
    c.version, c.ops = version, list(ops) or [element_op()]
    c.num_ops = len(c.ops)
    return c.encode()


FORGED_CHANGES = {
    "ops[0].element.skiros:PositionX[0]": [element_op(values=[value(f=f)]) for f in NOT_FINITE],
    "ops[0].element.skiros:PositionX[1].type": [element_op(values=[value(), value(kind=9)])],  # a KeyError before
    "ops[0].kind": [element_op(kind=7)],
    "ops[0].element.id": [element_op(eid="")],
    "ops[1].relation.subject": [relation_op(s="")],
}


@pytest.mark.parametrize("field", FORGED_CHANGES)
def test_a_change_with_bad_values_is_not_applied_and_the_replica_resyncs(replica, field):
    for forged in FORGED_CHANGES[field]:
        ops = (element_op(eid="skiros:Cube-3"), forged) if field.startswith("ops[1]") else (forged,)
        replica._stale = False
        replica._on_change(change(4, *ops))
        assert replica.version == 3 and not replica._elements and not replica._relations
        assert replica._stale  # it needs version 4: the next read takes the server's snapshot
    assert replica.rejects.summary() == {kind_of("SB_WM_CHANGES", field): len(FORGED_CHANGES[field])}


def test_a_change_with_a_version_before_any_is_counted_and_changes_nothing(replica):
    replica._on_change(change(-5))
    replica._on_change(change(0))
    assert replica.version == 3 and not replica._stale and replica.rejects.total == 2
    replica._on_change(change(4, element_op(), relation_op()))  # and a good one is applied
    assert replica.version == 4 and replica.get_element("skiros:Cube-2").getProperty("skiros:PositionX").value == 0.5


def test_a_transaction_result_for_a_request_never_made_is_not_kept(replica):
    replica._txn_ids = 2
    for rid in (1, 3, 10 ** 12, -1):
        r = wm_commit_t()
        r.client_id, r.request_id, r.request_digest = replica._txn_client_id, rid, bytes(32)
        replica._on_result(StampedMessage("SB_WM_TXN_RESULT", Stamp(1, 0, "wm", 0), r.encode()))
    assert list(replica.results) == [1]
    assert replica.rejects.summary() == {"SB_WM_TXN_RESULT: request_id": 3}


# -- the lockstep clock and stamps -----------------------------------------------------------------------

def clock(frame: int, sim_time_ns: int, counts=()) -> bytes:
    c = lockstep_clock_t()
    c.header = header_t()
    c.header.frame, c.header.sim_time_ns, c.header.sender = frame, sim_time_ns, "sim"
    c.frame_period_ns = 10_000_000
    c.participants, c.num_participants = ["me"], 1
    c.counts = []
    for sender, ch, f, n in counts:
        cc = channel_count_t()
        cc.sender, cc.channel, cc.frame, cc.count = sender, ch, f, n
        c.counts.append(cc)
    c.num_counts = len(c.counts)
    return c.encode()


def test_a_clock_whose_time_runs_backwards_or_whose_counts_are_nonsense_is_counted_not_taken():
    p = LockstepParticipant(open_bus("memq://"), "me")
    p._on_clock("SB_LOCKSTEP_CLOCK", clock(0, -10_000_000))  # before the start of time
    assert p._next_clock is None
    p._on_clock("SB_LOCKSTEP_CLOCK", clock(0, 20_000_000))
    assert p._next_clock is not None
    p._next_clock, p._last_acked = None, 0  # frame 0 done: frame 1 is due
    for forged in (clock(1, 10_000_000),                                     # backwards
                   clock(1, 30_000_000, [("wm", "SB_WM_CHANGES", 0, -3)]),    # a negative count
                   clock(1, 30_000_000, [("wm", "SB_WM_CHANGES", 9, 1)])):    # a frame after this one
        p._on_clock("SB_LOCKSTEP_CLOCK", forged)
        assert p._next_clock is None
    assert p.bad_input.total == 4
    p._on_clock("SB_LOCKSTEP_CLOCK", clock(1, 30_000_000, [("wm", "SB_WM_CHANGES", 0, 1)]))
    assert p._next_clock.header.sim_time_ns == 30_000_000


def test_a_stamp_with_a_negative_sim_time_is_no_stamp():
    h = sim_state_t()
    h.header = header_t()
    h.header.frame, h.header.sim_time_ns, h.header.sender, h.header.seq = 3, -1, "sim", 0
    assert peek_stamp(h.encode()) is None
    h.header.sim_time_ns = 0
    assert peek_stamp(h.encode()) == Stamp(3, 0, "sim", 0)


# -- a skill process's ticks and expansions ------------------------------------------------------------

class Reach(SkillDescription):
    def createDescription(self):
        self.addParam("Speed", 0.5, ParamTypes.Optional)
        self.addParam("Via", [0.0], ParamTypes.Optional)


class reach(PrimitiveBase):
    started: list = []

    def createDescription(self):
        self.setDescription(Reach(), self.__class__.__name__)

    def onStart(self):
        reach.started.append(self.params["Speed"].value)
        return True

    def execute(self):
        return self.success("reached")


class Twice(SkillDescription):
    def createDescription(self):
        self.addParam("Speed", 0.5, ParamTypes.Optional)


class twice(SkillBase):
    def createDescription(self):
        self.setDescription(Twice(), self.__class__.__name__)

    def expand(self, skill):
        skill.setProcessor(SerialStar())
        skill(self.skill("Reach", ""), self.skill("Reach", ""))


def tick(action=skill_tick_t.START, frame=-1, sim_time_ns=0, values=None, key="Speed") -> skill_tick_t:
    t = skill_tick_t()
    t.label = "reach" if action != skill_tick_t.EXPAND else "twice"
    t.instance, t.action, t.frame, t.sim_time_ns = 1, action, frame, sim_time_ns
    p = skill_param_t()
    p.key, p.data_type = key, "float"
    p.values = values if values is not None else [skill_value(f=0.25)]
    p.num_values = len(p.values)
    t.params, t.num_params = [p], 1
    return wire(t)


def skill_value(kind=skill_value_t.FLOAT, f=0.0, s="", element=None) -> skill_value_t:
    v = skill_value_t()
    v.type, v.f, v.s = kind, f, s
    v.element = element or wm_element_t()
    return v


def nan_element() -> wm_element_t:
    return element_op(eid="", values=[value(f=math.nan)]).element


FORGED_TICKS = {
    "params.Speed[0]": [tick(values=[skill_value(f=f)]) for f in NOT_FINITE],
    "params.Speed[0].type": [tick(values=[skill_value(kind=12)])],
    "params.Via[0]": [tick(key="Via", values=[skill_value(skill_value_t.JSON, s=s)])
                      for s in ("[NaN]", '{"x": Infinity}', "[1.0,")],
    "params.Speed[0].skiros:PositionX[0]": [tick(values=[skill_value(skill_value_t.ELEMENT, element=nan_element())])],
    "frame": [tick(frame=-7)],
    "sim_time_ns": [tick(sim_time_ns=-1)],
    "action": [tick(action=9)],
}


@pytest.fixture
def process():
    reach.started.clear()
    proc = SkillProcess(open_bus("memq://"), "t", [__name__])
    assert sorted(proc.classes) == ["reach", "twice"], proc.errors
    return proc


@pytest.mark.parametrize("field", FORGED_TICKS)
def test_a_tick_with_bad_values_is_refused_and_the_skill_never_runs(process, field):
    for t in FORGED_TICKS[field]:
        r = process.on_tick(t)
        assert r.state == int(State.Failure) and "refused the tick" in r.message and r.code == -1
    assert reach.started == [] and process.instances == {}
    assert process.rejects.summary() == {kind_of("SKPROC_T.tick", field): len(FORGED_TICKS[field])}
    assert process.on_tick(tick()).state == int(State.Success) and reach.started == [0.25]  # a sane one runs


def test_an_expansion_with_bad_values_is_refused(process):
    r = process.on_expand(tick(skill_tick_t.EXPAND, values=[skill_value(f=math.nan)]))
    assert "refused the expansion of 'twice'" in r.error and r.num_nodes == 0
    assert process.rejects.summary() == {"SKPROC_T.expand: params.Speed[]": 1}
    assert process.on_expand(tick(skill_tick_t.EXPAND)).error == ""


# -- the physics script player (skillbus sim-script) ------------------------------------------------

def test_the_script_player_records_no_state_with_values_that_are_not_finite():
    p = LockstepParticipant(open_bus("memq://"), "script")
    player = ScriptPlayer(p, {"steps": [], "record_every": 1})

    def state(**change) -> StampedMessage:
        s = sim_state_t()
        s.header = header_t()
        s.header.sender = "sim"
        for k, v in change.items():
            setattr(s, k, v)
        return StampedMessage("SB_SIM_STATE", Stamp(0, 0, "sim", 0), s.encode())

    player.on_state(state(finger_width=0.04))
    for forged in (state(finger_width=math.nan), state(finger_force=math.inf),
                   state(num_joints=1, joint_names=["j"], position=[math.nan], velocity=[0.0], effort=[0.0])):
        player.on_state(forged)
    assert len(player.states) == 1 and player.last_msg.finger_width == 0.04
    assert player.bad == 3
    assert player.rejects.summary() == {"SB_SIM_STATE: finger_force": 1, "SB_SIM_STATE: finger_width": 1,
                                        "SB_SIM_STATE: position[]": 1}
