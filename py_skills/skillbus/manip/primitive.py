"""Each registered manipulation skill as a skill of the skill manager: a description
(``Manip<Name>``: the parameters Arm, Gripper, Config, the skill's element parameters and
its scalar defaults, its conditions) and a primitive (``manip_<key>``) that runs the
command list with the executor, one step per tick. So a manipulation-command skill has
parameters, conditions, preemption and progress like any other, and composes with
processors into trees.

``skills_module(module_name)`` makes the classes for every registered skill, named into
that module (the skill process loads the classes a library module defines):
skillbus.manip.library is such a module.
"""

from __future__ import annotations

import logging
import time
from typing import Any

from skillbus import tick_context
from skillbus.manip import config as manip_config
from skillbus.manip.executor import ManipExecutor
from skillbus.manip.registry import SKILLS
from skillbus.manip.views import Controller, RobotInfo, TaskView, ViewError
from skillbus.skill import Element, ParamTypes, PrimitiveBase, SkillDescription, State


log = logging.getLogger("skillbus.manip")


def camel(key: str) -> str:
    return "".join(w.capitalize() for w in key.split("_"))


def _robot_base(wmi: Any, arm_id: str) -> tuple[Any, str]:
    """The arm's robot element and its world pose (the base frame); the world frame when
    the world model names no robot for the arm."""
    identity = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    if wmi is None:
        return identity, ""
    from skillbus.world.poses import world_pose
    robots = [r["src"] for r in wmi.get_relations("", "skiros:hasA", arm_id)]
    if not robots:
        return identity, ""
    return world_pose(wmi, robots[0]), robots[0]


def _service(getter: Any) -> Any:
    try:
        return getter()
    except Exception:
        return None


class _ManipPrimitive(PrimitiveBase):
    manip_class: Any = None

    def createDescription(self):  # bound per skill by make_classes
        raise NotImplementedError

    def _cfg(self) -> dict:
        cls = self.manip_class
        params: dict[str, Any] = {}
        for key, default in cls.defaults.items():  # a parameter left at its default does not hide the YAML's value
            if key in self.params and self.params[key].value is not None and self.params[key].value != default:
                params[key] = self.params[key].value
        for key in list(cls.elements) + list(cls.optional_elements):
            e = self.params[key].value if key in self.params else None
            if e is not None and getattr(e, "id", ""):
                params[key] = e.id
        cfg = manip_config.merge(cls.defaults, self.params["Config"].value or "", params)
        refused = cls.keys_refused(cfg)
        if refused:  # (a typo would be ignored and the default act: refused, named)
            raise manip_config.ConfigError(f"configuration: {refused}")
        return cfg

    def onStart(self):
        from skillbus.robot import arm as arm_service
        cls = self.manip_class
        try:
            cfg = self._cfg()
        except manip_config.ConfigError as e:
            self.message = f"{cls.key}: {e}"
            return False
        try:
            arm = arm_service.arm()
        except arm_service.ArmError as e:
            self.message = f"{cls.key}: {e}"
            return False
        arm_id = self.params["Arm"].value.id
        gripper = self.params["Gripper"].value
        gripper_id = gripper.id if gripper is not None else ""
        base, robot_id = _robot_base(self.wmi, arm_id)
        from skillbus.can import gripper_service
        from skillbus.robot import interfaces
        self.controller = Controller(arm, base)
        task = TaskView(base, self.wmi, _service(lambda: interfaces.get("camera")),
                        _service(lambda: interfaces.get("articulation")))
        self.skill = cls(RobotInfo(arm_id, gripper_id, robot_id), self.controller, task, cfg)
        try:
            self.skill.simple_generate_manip_cmds()
        except (ViewError, ValueError, KeyError) as e:
            self.message = f"{cls.key}: cannot build its commands: {e}"
            return False
        self.executor = ManipExecutor(self.skill, self.controller, tick_context.now_s, self._command_id,
                                      _service(gripper_service.driver), _service(lambda: interfaces.get("attach")))
        self.writing = False
        return True

    @staticmethod
    def _command_id(label: str) -> str:
        tick = tick_context.current_tick()
        return f"{label}@{tick.frame}" if tick is not None else f"{label}@{time.monotonic_ns()}"

    def execute(self):
        if self.writing:
            result = self.wmi.results.get(self.write_request) if self.write_request is not None else None
            if result is not None and result.error:  # (before, never looked at: it waited for ever)
                return self.fail(f"{self.skill.key}: the world model refused what it did: {result.error}", -1)
            if self.skill.world_shows():
                return self.success(self.done_message)
            if tick_context.now_s() - self.writing_since > self.executor.timeout_s:
                return self.fail(f"{self.skill.key}: the world model does not show what it did after "
                                 f"{self.executor.timeout_s:.0f} s (another writer changed it?)", -2)
            return self.step(f"{self.skill.key}: writing what it did into the world model")
        out = self.executor.tick()
        self.progress = self.executor.progress
        if out.state == "running":
            return self.step(out.message)
        if out.state == "failure":
            return self.fail(out.message, out.code or -1)
        ops = self.skill.world_ops() if self.wmi is not None else []
        if ops:
            from skillbus.rpc import RpcError, RpcTimeout
            from skillbus.world.client import WorldModelError
            try:  # (under lockstep with this frame, its result heard later; else at once)
                self.write_request = self.wmi.commit_async(ops) if self.wmi.participant is not None else None
                if self.write_request is None:
                    self.wmi.commit(ops)
            except RpcTimeout:
                pass  # (applied or not, unknown: the replica showing it, or the deadline, decides)
            except (WorldModelError, RpcError) as e:
                return self.fail(f"{self.skill.key}: the world model refused what it did: {e}", -1)
            self.writing, self.done_message = True, out.message
            self.writing_since = tick_context.now_s()
            return self.step(f"{self.skill.key}: writing what it did into the world model")
        return self.success(out.message)

    def onEnd(self):
        """Ended another way than by the executor's own outcome (the skill process ends a
        primitive whose execute() raised): a trajectory still played is stopped, and the
        log says so (the failure's message is the exception's)."""
        executor = getattr(self, "executor", None)
        if executor is not None and self.state != State.Success:
            said = executor.stop_motion()
            if said:
                log.warning("%s ended by a failure: %s", self.skill.key, said)
        return True

    def onPreempt(self):
        """Stopped: the arm holds where it is (a command in flight is replaced)."""
        try:
            if getattr(self, "executor", None) is not None:
                self.executor.phase = "stopped"  # (held here: onEnd does not hold again)
            self.controller.arm.hold(self._command_id(f"{self.skill.key}-stop"))
        except Exception as e:
            return self.fail(f"preempted: {self.skill.key}: the arm could not be stopped: {e}", -1)
        return self.fail(f"preempted: {self.skill.key} at command {self.executor.done_count + 1} of "
                         f"{self.executor.total}", -1)


def make_classes(key: str, cls: Any, module: str) -> tuple[type, type]:
    """The description and the primitive of the registered skill `key`."""
    def create(self):
        self.addParam("Arm", Element("skiros:Arm"), ParamTypes.Required)
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Optional,
                      description="needed by open_gripper and close_gripper")
        self.addParam("Config", "", ParamTypes.Optional,
                      description="YAML text or a .yaml file: the skill's configuration (skillbus.manip.config)")
        for name, concept in cls.elements.items():
            self.addParam(name, Element(concept), ParamTypes.Required)
        for name, concept in cls.optional_elements.items():
            self.addParam(name, Element(concept), ParamTypes.Optional)
        for name, value in cls.defaults.items():
            if isinstance(value, (bool, int, float, str)):
                self.addParam(name, value, ParamTypes.Optional)
        cls.describe(self)

    desc = type(f"Manip{camel(key)}", (SkillDescription,), {"createDescription": create, "__module__": module,
                                                           "__doc__": cls.__doc__})

    def bind(self):
        self.setDescription(desc(), f"manip_{key}")

    prim = type(f"manip_{key}", (_ManipPrimitive,), {"createDescription": bind, "manip_class": cls,
                                                     "__module__": module, "__doc__": cls.__doc__})
    return desc, prim


def skills_module(module: str) -> dict[str, type]:
    """Classes for every registered skill, by class name, for a library module's globals()."""
    out: dict[str, type] = {}
    for key, cls in sorted(SKILLS.items()):
        d, p = make_classes(key, cls, module)
        out[d.__name__] = d
        out[p.__name__] = p
    return out
