"""Skill implementations: PrimitiveBase (runs in a skill process, ticked by the manager)
and SkillBase (a compound: expand() describes a tree that the manager executes).

    class open_gripper(PrimitiveBase):
        def createDescription(self):
            self.setDescription(GripperMove(), self.__class__.__name__)

        def execute(self):
            if not self.started_moving:
                return self.step("moving")
            return self.success("open")

    class pick(SkillBase):
        def createDescription(self):
            self.setDescription(Pick(), self.__class__.__name__)

        def expand(self, skill):
            skill.setProcessor(SerialStar())
            skill(
                self.skill("MoveArm", "", remap={"Target": "Object"}),
                self.skill("GripperMove", "close", specify={"Width": 0.0}),
            )
"""

from __future__ import annotations

import copy
import enum
from typing import Any

from skillbus.msgs import skill_state_t
from skillbus.skill.description import SkillDescription
from skillbus.skill.params import ParamHandler
from skillbus.skill.processors import Processor, SerialStar


class State(enum.IntEnum):
    """A skill's state; the numbers are the IDL's (lcmtypes/skill_state_t.lcm)."""
    Uninitialized = skill_state_t.UNINITIALIZED
    Idle = skill_state_t.IDLE
    Running = skill_state_t.RUNNING
    Success = skill_state_t.SUCCESS
    Failure = skill_state_t.FAILURE


class SkillCore:
    """What primitives and compound skills share: a description, a label, parameters."""

    def __init__(self) -> None:
        self._description: SkillDescription | None = None
        self._label = ""
        self.params = ParamHandler()
        self.wmi: Any = None  # the world-model interface, set by the skill process
        self.createDescription()
        if self._description is None:
            raise ValueError(f"{type(self).__name__}.createDescription() must call self.setDescription(...)")

    def createDescription(self) -> None:
        """Override: call self.setDescription(Description(), label)."""

    def setDescription(self, description: SkillDescription, label: str = "") -> None:
        if not isinstance(description, SkillDescription):
            raise TypeError(f"setDescription wants a SkillDescription, got {type(description).__name__}")
        self._description = description
        self._label = label or type(self).__name__
        self.params = ParamHandler()
        self.params._params = description.params.getCopy()

    @property
    def wm(self) -> Any:
        return self.wmi

    @property
    def description(self) -> SkillDescription:
        assert self._description is not None
        return self._description

    @property
    def type(self) -> str:
        return self.description.type

    @property
    def label(self) -> str:
        return self._label


class PrimitiveBase(SkillCore):
    """A skill that acts. Hooks (override what you need): onInit (once, at load; False:
    not loaded), onStart (before the first execute; False: the start fails), execute
    (every tick; must not block), onPreempt (asked to stop; returns a result like
    execute), onEnd (after the last execute), onReset."""

    def __init__(self) -> None:
        super().__init__()
        self.state = State.Idle
        self.message = ""
        self.code = 0
        self.progress = 0.0

    def onInit(self) -> bool:
        return True

    def onStart(self) -> bool:
        return True

    def execute(self) -> State:
        return self.success("done")

    def onPreempt(self) -> State:
        return self.fail("preempted", -1)

    def onEnd(self) -> bool:
        return True

    def onReset(self) -> None:
        pass

    # -- results: set state, message and code, and return the state ---------------
    def step(self, msg: str = "") -> State:
        return self._result(State.Running, msg, 0)

    def success(self, msg: str = "") -> State:
        return self._result(State.Success, msg, 0)

    def fail(self, msg: str, code: int) -> State:
        if not isinstance(code, int):
            raise TypeError(f"fail(msg, code): code must be an int, got {type(code).__name__}")
        return self._result(State.Failure, msg, code)

    def _result(self, state: State, msg: str, code: int) -> State:
        self.state, self.message, self.code = state, msg, code
        return state


class SkillWrapper:
    """A node of a compound skill's tree: a placeholder for a skill type (resolved to an
    implementation when the tree starts) or an anonymous group under a processor.
    Calling it adds children: ``node(child1, child2)``."""

    def __init__(self, type_: str = "", label: str = "", remap: dict | None = None,
                 specify: dict | None = None, processor: Processor | None = None) -> None:
        self.type, self.label = type_, label
        self.remap = dict(remap or {})
        self.specify = dict(specify or {})
        self.processor: Processor = processor or SerialStar()  # SkiROS2's default (its code, not its wiki)
        self.children: list[SkillWrapper] = []

    def setProcessor(self, processor: Processor) -> None:
        if not isinstance(processor, Processor):
            raise TypeError(f"setProcessor wants a processor (Serial(), SerialStar(), ...), got {processor!r}")
        self.processor = processor

    def __call__(self, *children: "SkillWrapper") -> "SkillWrapper":
        for c in children:
            if not isinstance(c, SkillWrapper):
                raise TypeError(f"a child of {self.type or self.processor.spec()} must come from self.skill(...), "
                                f"got {c!r}")
            self.children.append(c)
        return self

    def describe(self) -> dict:
        """The tree as plain data, for the skill manager."""
        return {"type": self.type, "label": self.label, "processor": self.processor.spec(),
                "remap": dict(self.remap), "specify": {k: _plain(v) for k, v in self.specify.items()},
                "children": [c.describe() for c in self.children]}


def _plain(v: Any) -> Any:
    from skillbus.world.element import Element
    if isinstance(v, Element):
        return {"element": v.id or v.type, "label": v.label}
    return copy.deepcopy(v)


class SkillBase(SkillCore):
    """A compound skill: override expand(skill) to describe its tree."""

    def expand(self, skill: SkillWrapper) -> None:
        pass

    def skill(self, type_or_processor: str | Processor, label: str = "", remap: dict | None = None,
              specify: dict | None = None) -> SkillWrapper:
        if isinstance(type_or_processor, Processor):
            return SkillWrapper(processor=type_or_processor)
        if not isinstance(type_or_processor, str) or not type_or_processor:
            raise TypeError(f"self.skill wants a skill type name or a processor, got {type_or_processor!r}")
        return SkillWrapper(type_or_processor, label, remap, specify)

    def tree(self) -> SkillWrapper:
        """Runs expand() on a fresh root and returns the root (what the manager executes)."""
        root = SkillWrapper(self.type, self.label)
        self.expand(root)
        return root
