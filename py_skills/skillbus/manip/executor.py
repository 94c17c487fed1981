"""The executor of a manipulation command list, one step per skill tick (it never
blocks: a tick plans, sends or checks, and returns).

For the head command of ``skill.manip_list``:

1. **motion**: ``free`` and ``linear`` ask the motion service for a plan to the
   command's pose (converted from the base frame to the world); a plan that fails counts
   in ``controller.num_plan_failed`` and is asked again on the next tick until the skill's
   ``is_feasible()`` turns false, which fails the skill naming the last planning error.
   ``joints`` sends a joint target directly; ``none`` does not move. The arm must settle
   on the trajectory's end (the robot's reply and its state say so).
2. **action**: ``open_gripper``/``close_gripper`` command the gripper (its CANopen driver)
   and wait for its fingers to stop; ``attach_obj``/``detach_obj`` ask the physics server
   for a weld (skillbus.sim.attach) and wait for its answer; ``wait`` waits
   ``params["frames"]`` ticks; ``dummy_forward`` does nothing.
3. ``controller.head_finished`` turns true and the skill's ``is_done()`` pops the command
   (when its ``is_subtask_done()`` agrees).

When the list is empty the skill's ``is_success()`` decides between success and a
failure that names ``skill.failure_reason``. Each command must finish within
``cfg["command_timeout_s"]`` of sim time (20 s by default), counted from the end of its
trajectory as planned once the robot has taken it (a slow move is not a stuck one).

A failure (a timeout, a skill's method or an interface raising) while a trajectory is
being played stops the arm where it is (``arm.hold``), as a stop does: a failed skill
never leaves the arm moving on a command nobody watches any more (a motion the robot
refused moved nothing, and holds nothing).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from skillbus.manip.command import ManipCommand
from skillbus.manip.frames import angle_between

OPEN_UM, CLOSED_UM = 80_000, 0
SETTLE_RAD = 0.01


class PlanRefused(RuntimeError):
    pass


@dataclass
class Outcome:
    state: str      # running | success | failure
    message: str
    code: int = 0


class ManipExecutor:
    def __init__(self, skill: Any, controller: Any, now: Callable[[], float], command_id: Callable[[str], str],
                 gripper: Any = None, attacher: Any = None) -> None:
        self.skill, self.controller, self.now = skill, controller, now
        self.command_id, self.gripper, self.attacher = command_id, gripper, attacher
        self.total = max(1, len(skill.manip_list))
        self.done_count = 0
        self.timeout_s = float(skill.cfg.get("command_timeout_s", 20.0))
        self.checked = False  # the whole list, before its first command moves anything
        self._reset_head()
        self.log: list[str] = []   # one line per finished command (the episode recorder reads it)

    def _reset_head(self) -> None:
        self.phase = "motion"
        self.cmd_id: str | None = None
        self.action_sent = False
        self.action_ref: Any = None
        self.waited = 0
        self.refused = 0  # plans of the head command refused
        self.head_started = self.late_from = self.now()
        self.controller.head_finished = False
        self.controller.num_last_cmd = 0

    @property
    def progress(self) -> float:
        return min(1.0, self.done_count / self.total)

    def tick(self) -> Outcome:
        try:
            out = self._tick()
        except Exception as e:  # (a skill's or an interface's bug fails the skill, the arm stopped)
            out = Outcome("failure", f"{self.skill.key}: command {self.done_count + 1} raised "
                                     f"{type(e).__name__}: {e}", -1)
        if out.state == "failure":
            held = self.stop_motion()
            if held:
                out = Outcome(out.state, f"{out.message}; {held}", out.code)
        return out

    def stop_motion(self) -> str:
        """Stops a trajectory of the head command the robot may still be playing (once):
        what it did, for the failure's message ("" when nothing was moving)."""
        if self.phase != "motion" or self.cmd_id is None:
            return ""
        cid, self.cmd_id, self.phase = self.cmd_id, None, "stopped"
        try:
            self.controller.arm.hold(self.command_id(f"{self.skill.key}-hold"))
        except Exception as e:
            return f"the arm could not be stopped ({cid}): {e}"
        return "the arm was stopped where it was"

    def _deadline(self) -> float:
        """When the head command is late: `timeout_s` after it began, or after its
        trajectory's planned end once the robot has taken it."""
        if self.phase == "motion" and self.cmd_id is not None:
            not_done_before = getattr(self.controller.arm, "not_done_before", None)
            end = not_done_before(self.cmd_id) if not_done_before is not None else None
            if end is not None:
                self.late_from = max(self.late_from, end)
        return self.late_from + self.timeout_s

    def _tick(self) -> Outcome:
        skill = self.skill
        try:
            skill.update()
        except Exception as e:
            return Outcome("failure", f"{skill.key}: update() raised {type(e).__name__}: {e}", -1)
        if not self.checked:
            self.checked = True
            for i, entry in enumerate(skill.manip_list):
                try:
                    ManipCommand.from_entry(entry)
                except ValueError as e:  # (before, found when it came: after the commands before it had run)
                    return Outcome("failure", f"{skill.key}: command {i + 1} of {len(skill.manip_list)}: {e} "
                                              "(nothing was run)", -1)
        if not skill.manip_list:
            return self._finish()
        try:
            cmd = ManipCommand.from_entry(skill.manip_list[0])
        except ValueError as e:
            return Outcome("failure", f"{skill.key}: command {self.done_count + 1}: {e}", -1)
        self.controller.num_last_cmd += 1
        if self.now() > self._deadline():
            return Outcome("failure", f"{skill.key}: command {self.done_count + 1} ({cmd.describe()}) did not finish "
                                      f"within {self.timeout_s:.0f} s ({self.phase})", -2)
        where = f"command {self.done_count + 1}/{self.total}: {cmd.describe()}"
        if self.phase == "motion":
            out = self._motion(cmd)
            if out is not None:
                return out if out.state != "running" else Outcome("running", f"{where}: {out.message}")
            self.phase = "action"
        if self.phase == "action":
            out = self._action(cmd)
            if out is not None:
                return out if out.state != "running" else Outcome("running", f"{where}: {out.message}")
            self.phase = "done"
            self.controller.head_finished = True
        before = len(skill.manip_list)
        try:
            empty = skill.is_done()
        except Exception as e:
            return Outcome("failure", f"{skill.key}: is_done() raised {type(e).__name__}: {e}", -1)
        if len(skill.manip_list) < before:
            self.log.append(cmd.describe())
            self.done_count += 1
            self._reset_head()
        if empty:
            return self._finish()
        return Outcome("running", f"{where}: done")

    def _finish(self) -> Outcome:
        skill = self.skill
        try:
            ok = skill.is_success()
        except Exception as e:
            return Outcome("failure", f"{skill.key}: is_success() raised {type(e).__name__}: {e}", -1)
        if ok:
            return Outcome("success", f"{skill.key}: {self.done_count} command(s) done")
        return Outcome("failure", f"{skill.key}: not successful: {skill.failure_reason or 'is_success() said no'}", -4)

    # -- motion ------------------------------------------------------------------------
    def _at(self, cmd: ManipCommand) -> bool:
        """Whether the tool is already at the command's pose (gripper actions at the
        current pose need no motion)."""
        try:
            p, q = self.controller.get_ee_pose()
        except Exception:
            return False
        dp = sum((a - b) ** 2 for a, b in zip(p, cmd.position)) ** 0.5
        return dp < 0.002 and angle_between(q, cmd.quaternion) < 0.01

    def _motion(self, cmd: ManipCommand) -> Outcome | None:
        arm = self.controller.arm
        motion = cmd.motion
        if self.cmd_id is None:
            if motion == "none" or (motion != "joints" and self._at(cmd)):
                return None
            cid = self.command_id(f"{self.skill.key}{self.done_count + 1}")
            speed = cmd.speed if cmd.speed is not None else float(self.skill.cfg.get("speed", 0.5))
            if motion == "joints":
                err = self._joint_move(cid, cmd.params["joints"], speed)
                if err:
                    return Outcome("failure", f"{self.skill.key}: {err}", -1)
            else:
                p, q = self.controller.to_world(cmd.position, cmd.quaternion)
                # A straight line the planner refused (a wrist flip on the way) may be allowed
                # to become a joint-space move on the next try: short steps, nearly straight.
                linear = motion == "linear" and not (self.refused and cmd.params.get("fallback") == "free")
                try:
                    plan = arm.plan(list(p) + list(q), cartesian=linear, speed_scale=speed)
                    if not plan.ok:
                        raise PlanRefused(plan.error or "the motion service found no plan")
                except Exception as e:  # the motion service's refusal (no IK, a collision) or its silence
                    self.controller.num_plan_failed += 1
                    self.refused += 1
                    self.controller.last_plan_error = str(e)
                    if not self.skill.is_feasible():
                        return Outcome("failure", f"{self.skill.key}: not feasible: {self.controller.num_plan_failed} "
                                                  f"planning failure(s), the last: {e}", -5)
                    return Outcome("running", f"planning failed ({e}); planning again")
                arm.execute(plan, cid)
            self.cmd_id = cid
            return Outcome("running", "moving")
        done, error = arm.finished(self.cmd_id, float(cmd.params.get("settle_rad", SETTLE_RAD)))
        if error:
            self.cmd_id = None  # (refused: nothing moves, nothing to stop)
            return Outcome("failure", f"{self.skill.key}: the robot refused the motion: {error}", -1)
        return None if done else Outcome("running", "moving")

    def _joint_move(self, cid: str, targets: dict, speed: float) -> str:
        from skillbus.robot.messages import traj_point
        arm = self.controller.arm
        names, now = arm.joint_names(), arm.joints()
        unknown = [n for n in targets if n not in names]
        if unknown:
            return f"joint_ctrl: unknown joint(s) {', '.join(map(str, unknown))} (the arm has {', '.join(names)})"
        goal = [float(targets.get(n, q)) for n, q in zip(names, now)]
        span = max(abs(g - q) for g, q in zip(goal, now))
        duration = max(0.2, span / (1.0 * speed))  # rad/s: a slow joint-space move
        arm.send_joints(cid, names, [traj_point(duration, goal)])  # (from where the arm is: its reference now)
        return ""

    # -- actions -----------------------------------------------------------------------
    def _action(self, cmd: ManipCommand) -> Outcome | None:
        a = cmd.action
        if a == "dummy_forward":
            return None
        if a == "wait":
            self.waited += 1
            return None if self.waited > int(cmd.params.get("frames", 10)) else Outcome("running", "waiting")
        if a in ("open_gripper", "close_gripper"):
            return self._gripper(a, cmd)
        return self._attach(a == "attach_obj", str(cmd.params.get("object", "")))

    def _gripper(self, action: str, cmd: ManipCommand) -> Outcome | None:
        g = self.gripper
        if g is None:
            return Outcome("failure", f"{self.skill.key}: {action}: this skill process has no gripper "
                                      "(--gripper CHANNEL:NODE)", -1)
        s = g.status()
        if s.faults:
            return Outcome("failure", f"{self.skill.key}: {action}: gripper fault: {s.faults[-1]}", -3)
        if not self.action_sent:
            width = cmd.params.get("width")
            um = OPEN_UM if action == "open_gripper" else CLOSED_UM
            if width is not None and action == "open_gripper":
                um = int(round(min(max(float(width), 0.0), OPEN_UM / 1e6) * 1e6))
            g.command(um)
            self.action_sent = True
            self.action_ref = self.now()
            return Outcome("running", f"{action}: sent")
        if not s.fresh or s.moving:
            return Outcome("running", f"{action}: width {s.position_um / 1000:.1f} mm")
        if action == "open_gripper" and not s.target_reached:
            return Outcome("running", f"{action}: width {s.position_um / 1000:.1f} mm")
        if self.now() - self.action_ref < 0.1:  # the status of the set-point, not the one before it
            return Outcome("running", f"{action}: width {s.position_um / 1000:.1f} mm")
        self.gripped = s.gripped
        return None

    def _attach(self, attach: bool, obj: str) -> Outcome | None:
        what = "attach_obj" if attach else "detach_obj"
        if self.attacher is None:
            return Outcome("failure", f"{self.skill.key}: {what}: this skill process has no attach interface "
                                      "(--interface attach=skillbus.sim.attach; a simulator's weld, for data "
                                      "generation)", -1)
        if not self.action_sent:
            self.action_ref = self.attacher.request(attach, obj, self.command_id(f"{self.skill.key}{self.done_count + 1}"))
            self.action_sent = True
            return Outcome("running", f"{what} {obj}: sent")
        r = self.attacher.result(self.action_ref)
        if r is None:
            return Outcome("running", f"{what} {obj}: waiting for the physics server")
        accepted, error = r
        if not accepted:
            return Outcome("failure", f"{self.skill.key}: {what} {obj}: refused: {error}", -1)
        return None

