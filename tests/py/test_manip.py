"""The manipulation-command skill SDK (skillbus.manip) without a robot: the registry, the
command entries, the configuration, and the executor driving a command list against a
stand-in arm, gripper and attach interface (fakes only here, in a unit test; the family's
skills run against the real physics in tests/integration/test_manip_skills.py)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from skillbus.manip import ManipCommand, ManipSkill, register_skill, skill_key
from skillbus.manip import config as manip_config
from skillbus.manip.executor import ManipExecutor
from skillbus.manip.family.geometry import rotate_about, top_down
from skillbus.manip.views import Controller

IDENTITY = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))


class FakeArm:
    """Plans refuse targets whose x is above `reach`; an accepted trajectory ends `ticks`
    checks later with the tool at its target."""

    def __init__(self, reach: float = 1.0, ticks: int = 2) -> None:
        self.tool = [0.3, 0.0, 0.5, 0.0, 1.0, 0.0, 0.0]
        self.reach, self.ticks = reach, ticks
        self.plans: list[tuple[list[float], bool]] = []
        self.sent: dict[str, list] = {}
        self.checks: dict[str, int] = {}
        self.refuse_next = ""
        self.refuse_linear = 0

    @property
    def state(self):
        return SimpleNamespace(tool_pose=list(self.tool))

    def plan(self, target, cartesian=False, speed_scale=0.5):
        self.plans.append((list(target), cartesian))
        if cartesian and self.refuse_linear > 0:
            self.refuse_linear -= 1
            return SimpleNamespace(ok=False, error="a joint jumps", target=list(target))
        if target[0] > self.reach:
            raise RuntimeError(f"no inverse kinematics for x {target[0]:.2f}")
        if target[1] < -5:
            return SimpleNamespace(ok=False, error="outside the workspace", target=list(target))
        return SimpleNamespace(ok=True, error="", target=list(target))

    def execute(self, plan, cid):
        self.sent[cid] = plan.target

    def finished(self, cid, tolerance=0.01):
        if self.refuse_next:
            return True, self.refuse_next
        self.checks[cid] = self.checks.get(cid, 0) + 1
        if self.checks[cid] >= self.ticks:
            self.tool = list(self.sent[cid])
            return True, ""
        return False, ""

    def joint_names(self):
        return ["j1"]

    def joints(self):
        return [0.0]


class FakeGripper:
    def __init__(self) -> None:
        self.commands: list[int] = []
        self.faults: list[str] = []

    def command(self, um):
        self.commands.append(um)

    def status(self):
        return SimpleNamespace(faults=self.faults, fresh=True, moving=False, target_reached=True, gripped=False,
                               position_um=self.commands[-1] if self.commands else 0)


class FakeAttacher:
    def __init__(self, refuse: str = "") -> None:
        self.requests: list[tuple[bool, str]] = []
        self.refuse = refuse

    def request(self, attach, obj, label):
        self.requests.append((attach, obj))
        return label

    def result(self, rid):
        return (not self.refuse, self.refuse)


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        self.t += 0.02
        return self.t


@register_skill
class UnitPickLike(ManipSkill):
    defaults = {"x": 0.4}

    def simple_generate_manip_cmds(self):
        q = top_down(0.0)
        self.manip_list = [([self.cfg["x"], self.cfg.get("y", 0), 0.6], q, "open_gripper", {"motion": "free"}),
                           ([self.cfg["x"], 0, 0.45], q, "close_gripper",
                            {"motion": "linear", **({"fallback": "free"} if self.cfg.get("fallback") else {})}),
                           ([self.cfg["x"], 0, 0.45], q, "attach_obj", {"motion": "none", "object": "red"}),
                           ([self.cfg["x"], 0, 0.6], q, "dummy_forward", {"motion": "linear"})]


def run(skill_cfg: dict, arm=None, gripper=None, attacher=None, max_ticks: int = 200):
    arm = arm or FakeArm()
    controller = Controller(arm, IDENTITY)
    skill = UnitPickLike(None, controller, None, {**UnitPickLike.defaults, **skill_cfg})
    skill.simple_generate_manip_cmds()
    ids = iter(range(10_000))
    ex = ManipExecutor(skill, controller, Clock(), lambda label: f"{label}@{next(ids)}", gripper, attacher)
    for _ in range(max_ticks):
        out = ex.tick()
        if out.state != "running":
            return out, ex, arm
    raise AssertionError(f"still running after {max_ticks} ticks: {out.message}")


def test_registry_keys_and_a_second_class_under_one_key_is_refused():
    assert skill_key("GotoPose") == skill_key("Goto_Pose") == "goto_pose"
    assert UnitPickLike.key == "unit_pick_like"

    class UnitPickLike2(ManipSkill):  # noqa: D401 (a different class, a clashing key)
        pass
    UnitPickLike2.__name__ = "UnitPickLike"
    with pytest.raises(ValueError, match="'unit_pick_like' is taken by"):
        register_skill(UnitPickLike2)
    with pytest.raises(TypeError, match="not a ManipSkill subclass"):
        register_skill(int)


def test_command_entries_are_checked_naming_what_is_wrong():
    c = ManipCommand.from_entry((np.array([0.4, 0.0, 0.5]), np.array([0.0, 0.0, 2.0, 0.0]), "close_gripper", {}, 0.3))
    assert c.quaternion == (0.0, 0.0, 1.0, 0.0) and c.speed == 0.3 and c.motion == "free"
    bad = [((0, 0), (1, 0, 0, 0), "dummy_forward", {}), "the position must be 3 numbers",
           ((0, 0, float("nan")), (1, 0, 0, 0), "dummy_forward", {}), "not finite",
           ((0, 0, 0), (1, 0, 0, 0), "teleport", {}), "unknown action 'teleport'",
           ((0, 0, 0), (1, 0, 0, 0), "dummy_forward", {"motion": "fly"}), "motion 'fly'",
           ((0, 0, 0), (1, 0, 0, 0), "dummy_forward", {"motion": "joints"}), "needs params\\['joints'\\]",
           ((0, 0, 0), (1, 0, 0, 0), "attach_obj", {}), "attach_obj needs params\\['object'\\]",
           ((0, 0, 0), (1, 0, 0, 0), "dummy_forward", {}, 2.0), "speed 2.0 must be in",
           "not a tuple", "expected \\(p, q, action, params"]
    for entry, why in zip(bad[::2], bad[1::2]):
        with pytest.raises(ValueError, match=why):
            ManipCommand.from_entry(entry)


def test_configuration_merges_defaults_yaml_and_parameters(tmp_path):
    f = tmp_path / "pick.yaml"
    f.write_text("approach: 0.2\nlift: 0.3\n")
    assert manip_config.merge({"approach": 0.1, "lift": 0.1, "x": 1}, str(f), {"lift": 0.4}) == \
        {"approach": 0.2, "lift": 0.4, "x": 1}
    with pytest.raises(manip_config.ConfigError, match="does not exist"):
        manip_config.load(str(tmp_path / "missing.yaml"))
    with pytest.raises(manip_config.ConfigError, match="not valid YAML"):
        manip_config.load("a: [1, 2")
    task = tmp_path / "task.yaml"
    task.write_text("skills:\n  - name: open\n  - distance: 1\n")
    with pytest.raises(manip_config.ConfigError, match="skills\\[1\\] must be a mapping with a 'name'"):
        manip_config.load_task(str(task))


def test_a_key_the_skill_does_not_read_is_refused_naming_it(tmp_path):
    # Before, `distnce: 0.3` (or an entry's own Arm) went into the Config unread: the drawer
    # opened the default 0.15 m with the task's arm and the task succeeded.
    import importlib
    importlib.import_module("skillbus.manip.library")  # (the family registered)
    from skillbus.manip.registry import get_skill
    from skillbus.manip.task import manip_task
    open_ = get_skill("open")
    assert open_.unknown_keys({"Object": "x", "distance": 0.3, "speed": 0.2, "command_timeout_s": 5}) == []
    assert open_.unknown_keys({"distnce": 0.3, "Arm": "skiros:Arm-9"}) == ["Arm", "distnce"]
    assert get_skill("goto_pose").unknown_keys({"pose": [0] * 7}) == []  # (an option without a default)
    assert UnitPickLike.unknown_keys({"anything": 1}) == []  # a class that declares no options takes every key

    for entry, why in (("distnce: 0.3", "skills[0] (open): unknown key(s) distnce (it takes: Object, angle, approach, "
                                        "command_timeout_s, distance, max_plan_failures, speed, step_m, step_rad, "
                                        "success_fraction)"),
                       ("Arm: skiros:Arm-9", "skills[0] (open): Arm is the task's for every entry (give it to "
                                             "ManipTask), not an entry's")):
        task = tmp_path / "task.yaml"
        task.write_text(f"skills:\n  - name: open\n    Object: cabinet/drawer_joint\n    {entry}\n")
        skill = manip_task()
        skill.params["Task"].value = str(task)
        with pytest.raises(ValueError) as e:
            skill.expand(lambda *a, **k: None)
        assert str(e.value) == f"{task}: {why}", str(e.value)


def test_the_executor_plays_each_command_then_its_action_in_order():
    g, a = FakeGripper(), FakeAttacher()
    out, ex, arm = run({}, gripper=g, attacher=a)
    assert out.state == "success", out.message
    assert [linear for _, linear in arm.plans] == [False, True, True]  # the attach needs no motion
    assert g.commands == [80_000, 0] and a.requests == [(True, "red")]
    assert ex.done_count == 4 and ex.progress == 1.0
    assert arm.tool[:3] == [0.4, 0, 0.6]


def test_planning_failures_are_retried_until_the_skill_is_not_feasible():
    arm = FakeArm(reach=0.35)
    out, ex, _ = run({"max_plan_failures": 2}, arm=arm, gripper=FakeGripper(), attacher=FakeAttacher())
    assert out.state == "failure" and out.code == -5
    assert "not feasible: 3 planning failure(s), the last: no inverse kinematics for x 0.40" in out.message
    assert len(arm.plans) == 3 and ex.done_count == 0
    arm = FakeArm()
    arm.refuse_linear = 1
    out, _, _ = run({"fallback": "free"}, arm=arm, gripper=FakeGripper(), attacher=FakeAttacher())
    assert out.state == "success" and [linear for _, linear in arm.plans] == [False, True, False, True]
    out, _, _ = run({"max_plan_failures": 0, "y": -6}, gripper=FakeGripper(), attacher=FakeAttacher())
    assert out.state == "failure" and "the last: outside the workspace" in out.message  # a plan that is not ok


def test_what_the_robot_refuses_and_missing_interfaces_fail_naming_them():
    arm = FakeArm()
    arm.refuse_next = "joint1 beyond its limit"
    out, _, _ = run({}, arm=arm, gripper=FakeGripper(), attacher=FakeAttacher())
    assert out.state == "failure" and "the robot refused the motion: joint1 beyond its limit" in out.message
    out, _, _ = run({}, gripper=None, attacher=FakeAttacher())
    assert out.state == "failure" and "has no gripper (--gripper CHANNEL:NODE)" in out.message
    out, _, _ = run({}, gripper=FakeGripper(), attacher=None)
    assert out.state == "failure" and "no attach interface" in out.message
    out, _, _ = run({}, gripper=FakeGripper(), attacher=FakeAttacher(refuse="object 'red' is 0.30 m from the tool"))
    assert out.state == "failure" and "attach_obj red: refused: object 'red' is 0.30 m from the tool" in out.message
    g = FakeGripper()
    g.faults = ["EMCY 0x5000 following error"]
    out, _, _ = run({}, gripper=g, attacher=FakeAttacher())
    assert out.state == "failure" and "gripper fault: EMCY 0x5000" in out.message


class HoldingArm(FakeArm):
    """Says when its trajectories end (as the real arm does once the robot took one) and
    stops when asked."""

    def __init__(self, ticks: int, duration_s: float = 0.0, hold_error: str = "") -> None:
        super().__init__(ticks=ticks)
        self.duration_s, self.hold_error = duration_s, hold_error
        self.held: list[str] = []
        self.clock: Clock | None = None
        self.ends: dict[str, float] = {}

    def execute(self, plan, cid):
        super().execute(plan, cid)
        self.ends[cid] = self.clock.t + self.duration_s

    def not_done_before(self, cid):
        return self.ends.get(cid)

    def hold(self, cid):
        if self.hold_error:
            raise RuntimeError(self.hold_error)
        self.held.append(cid)
        return [0.0]


def run_holding(arm: HoldingArm, cfg: dict, max_ticks: int = 2000):
    """`run` with the arm told the executor's clock."""
    controller = Controller(arm, IDENTITY)
    skill = UnitPickLike(None, controller, None, {**UnitPickLike.defaults, **cfg})
    skill.simple_generate_manip_cmds()
    arm.clock = Clock()
    ids = iter(range(10_000))
    ex = ManipExecutor(skill, controller, arm.clock, lambda label: f"{label}@{next(ids)}", FakeGripper(),
                       FakeAttacher())
    for n in range(max_ticks):
        out = ex.tick()
        if out.state != "running":
            return out, ex, n
    raise AssertionError(f"still running after {max_ticks} ticks: {out.message}")


@register_skill
class UnitNanLift(ManipSkill):
    """Its third command's lift comes from the configuration."""

    def simple_generate_manip_cmds(self):
        q, grip = top_down(0.0), np.array([0.4, 0.0, 0.45])
        self.manip_list = [(grip + [0, 0, 0.1], q, "open_gripper", {"motion": "free"}),
                           (grip, q, "close_gripper", {"motion": "linear"}),
                           (grip + [0, 0, 0.1], q, self.cfg.get("action", "dummy_forward"),
                            {"motion": "linear", **self.cfg.get("params", {})})]


@pytest.mark.parametrize("params, why", [
    ({"width": float("nan")}, "params['width'] must be a finite number >= 0, not nan"),
    ({"settle_rad": float("nan")}, "params['settle_rad'] must be a finite number > 0, not nan"),
    ({"frames": -3}, "params['frames'] must be a whole number >= 0, not -3"),
    ({"frames": 2.5}, "params['frames'] must be a whole number >= 0, not 2.5"),
    ({"fallback": "teleport"}, "params['fallback'] can only be 'free', not 'teleport'"),
    ({"motion": "joints", "joints": {"joint1": float("inf")}}, "params['joints']['joint1'] must be a finite number"),
], ids=["width", "settle", "frames-negative", "frames-fraction", "fallback", "joints"])
def test_a_bad_command_anywhere_in_the_list_fails_the_skill_before_anything_moves(params, why):
    # Before, a bad third command was found when it came, after the first two had moved
    # the arm and closed the gripper; a NaN width raised from int(), a NaN settle_rad
    # never settled (a 20 s timeout "(motion)").
    arm, gripper = FakeArm(), FakeGripper()
    controller = Controller(arm, IDENTITY)
    skill = UnitNanLift(None, controller, None, {"action": "open_gripper" if "width" in params else "wait",
                                                 "params": params})
    skill.simple_generate_manip_cmds()
    ex = ManipExecutor(skill, controller, Clock(), lambda label: label, gripper, FakeAttacher())
    out = ex.tick()
    assert out.state == "failure" and out.message.startswith("unit_nan_lift: command 3 of 3: manip command: "), \
        out.message
    assert why in out.message and out.message.endswith("(nothing was run)"), out.message
    assert arm.sent == {} and gripper.commands == []


def test_a_command_that_never_finishes_times_out_naming_it_and_the_arm_is_stopped():
    # Before, the skill failed and the trajectory played on: no one stopped the arm.
    arm = HoldingArm(ticks=10_000)
    out, _, _ = run_holding(arm, {"command_timeout_s": 1.0})
    assert out.state == "failure" and out.code == -2
    assert "command 1 (open_gripper at (0.400 0.000 0.600) [free]) did not finish within 1 s (motion); " \
           "the arm was stopped where it was" in out.message
    assert list(arm.sent) == ["unit_pick_like1@0"] and arm.held == ["unit_pick_like-hold@1"]


def test_a_slow_trajectory_is_not_a_stuck_one():
    # A 3 s move with a 1 s timeout: late only 1 s after its planned end (it failed at 1 s).
    arm = HoldingArm(ticks=10_000, duration_s=3.0)
    out, _, ticks = run_holding(arm, {"command_timeout_s": 1.0})
    assert out.code == -2 and arm.held, out.message
    assert 195 <= ticks <= 205, ticks  # 4 s of 20 ms ticks
    arm = HoldingArm(ticks=150, duration_s=3.0)  # done after 3 s: every command finishes
    out, _, _ = run_holding(arm, {"command_timeout_s": 1.0})
    assert out.state == "success" and not arm.held, out.message


def test_a_failure_while_nothing_moves_holds_nothing_and_a_hold_that_fails_is_said():
    arm = HoldingArm(ticks=2)
    arm.refuse_next = ""
    out, _, _ = run_holding(arm, {"x": 5.0, "command_timeout_s": 1.0})  # no plan: never sent
    assert out.state == "failure" and arm.held == [] and "stopped" not in out.message, out.message
    arm = HoldingArm(ticks=10_000, hold_error="the robot does not answer")
    out, _, _ = run_holding(arm, {"command_timeout_s": 1.0})
    assert out.message.endswith("; the arm could not be stopped (unit_pick_like1@0): the robot does not answer")


def test_a_motion_the_robot_refuses_holds_nothing():
    arm = HoldingArm(ticks=2)
    arm.refuse_next = "joint1 target 9 is outside its limits"
    out, _, _ = run_holding(arm, {"command_timeout_s": 1.0})
    assert out.state == "failure" and "refused the motion" in out.message and arm.held == [], out.message


def test_a_bug_in_the_skill_while_moving_fails_it_and_stops_the_arm():
    arm = HoldingArm(ticks=10_000)
    controller = Controller(arm, IDENTITY)
    skill = UnitPickLike(None, controller, None, dict(UnitPickLike.defaults))
    skill.simple_generate_manip_cmds()
    arm.clock = Clock()
    ids = iter(range(100))
    ex = ManipExecutor(skill, controller, arm.clock, lambda label: f"{label}@{next(ids)}", FakeGripper(),
                       FakeAttacher())
    assert ex.tick().state == "running" and list(arm.sent)
    arm.finished = lambda cid, tolerance=0.01: 1 / 0  # (an interface's bug)
    out = ex.tick()
    assert out.state == "failure" and "raised ZeroDivisionError" in out.message and len(arm.held) == 1, out.message
    assert ex.stop_motion() == "" and len(arm.held) == 1  # once


def test_is_success_decides_and_its_reason_is_the_message():
    class Judged(UnitPickLike):
        def is_success(self):
            self.failure_reason = "the cube slipped"
            return False
    arm = FakeArm()
    controller = Controller(arm, IDENTITY)
    skill = Judged(None, controller, None, dict(UnitPickLike.defaults))
    skill.simple_generate_manip_cmds()
    ex = ManipExecutor(skill, controller, Clock(), lambda label: label, FakeGripper(), FakeAttacher())
    for _ in range(100):
        out = ex.tick()
        if out.state != "running":
            break
    assert out.state == "failure" and out.code == -4 and out.message.endswith("not successful: the cube slipped")


def test_a_door_handle_turns_with_the_door():
    hinge, axis = np.array([0.5, 0.0, 0.3]), np.array([0.0, 0.0, 1.0])
    p, q = rotate_about([0.5, 0.3, 0.3], axis, hinge, np.pi / 2, top_down(0.0))
    assert np.allclose(p, [0.2, 0.0, 0.3])
    assert np.allclose(np.abs(q), np.abs(top_down(np.pi / 2)))


class WritingSkill(UnitPickLike):
    """Says what it did into the world model when its commands are done."""

    def world_ops(self):
        from skillbus.msgs import wm_op_t
        return [wm_op_t()]

    def world_shows(self):
        return self.cfg.get("shows", False)


class Committing:
    """A lockstep world model client: commit_async returns request ids; results are what
    the test says the server answered."""

    def __init__(self) -> None:
        self.participant, self.results, self.sent = object(), {}, []

    def commit_async(self, ops):
        self.sent.append(ops)
        return len(self.sent)


def writing_primitive(cfg: dict):
    from skillbus.manip.executor import Outcome
    from skillbus.manip.primitive import make_classes
    _, prim = make_classes("writing_skill", WritingSkill, __name__)
    p = prim()
    p.skill = WritingSkill(None, None, None, {**WritingSkill.defaults, **cfg})
    p.executor = SimpleNamespace(tick=lambda: Outcome("success", "done"), progress=1.0, timeout_s=1.0)
    p.writing, p.wmi = False, Committing()
    return p


def test_the_world_model_refusing_what_a_skill_did_fails_it_naming_why():
    # Before, under lockstep the write's result was never looked at: a refused write left
    # the skill "writing what it did into the world model" for ever.
    from skillbus import tick_context
    from skillbus.msgs import wm_commit_t
    from skillbus.skill import State
    p = writing_primitive({})
    with tick_context.ticking(0, 0):
        assert p.execute() == State.Running and len(p.wmi.sent) == 1
    refused = wm_commit_t()
    refused.error = "skiros:Cube-2 changed meanwhile"
    p.wmi.results[1] = refused
    with tick_context.ticking(1, 20_000_000):
        assert p.execute() == State.Failure
    assert p.message == "unit_pick_like: the world model refused what it did: skiros:Cube-2 changed meanwhile"


def test_a_write_the_world_model_never_shows_fails_after_the_command_timeout():
    from skillbus import tick_context
    from skillbus.skill import State
    p = writing_primitive({})
    with tick_context.ticking(0, 0):
        assert p.execute() == State.Running
    p.wmi.results[1] = SimpleNamespace(error="")  # accepted, but the replica never shows it
    with tick_context.ticking(25, 500_000_000):
        assert p.execute() == State.Running
    with tick_context.ticking(60, 1_200_000_000):
        assert p.execute() == State.Failure
    assert "does not show what it did after 1 s" in p.message, p.message
    p = writing_primitive({"shows": True})
    with tick_context.ticking(0, 0):
        assert p.execute() == State.Running
    with tick_context.ticking(1, 20_000_000):
        assert p.execute() == State.Success and p.message == "done"
