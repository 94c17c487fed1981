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

As in SkiROS2 a skill has ``self.params`` / ``self._params`` (its ParamHandler),
``self.wmi`` / ``self._wmi`` (the world-model client) and a progress counter:
``self._progress_code`` is 0 when the skill has started, and each ``step`` and
``success`` adds one; ``fail(msg, code)`` sets a negative code. The skill process sends
the code and message to the manager with every tick (``skillbus run --json`` shows them).
"""

from __future__ import annotations

import enum
import itertools
import logging
import time
from datetime import datetime
from typing import Any

from skillbus.msgs import skill_state_t
from skillbus.skill.description import SkillDescription
from skillbus.skill.params import ParamHandler
from skillbus.skill.processors import Processor
from skillbus.skill.wrapper import SkillWrapper
from skillbus.world.element import Element

__all__ = ["PrimitiveBase", "SkillBase", "SkillCore", "SkillWrapper", "State"]

log = logging.getLogger("skillbus.skill")


class State(enum.IntEnum):
    """A skill's state; the numbers are the IDL's (lcmtypes/skill_state_t.lcm)."""
    Uninitialized = skill_state_t.UNINITIALIZED
    Idle = skill_state_t.IDLE
    Running = skill_state_t.RUNNING
    Success = skill_state_t.SUCCESS
    Failure = skill_state_t.FAILURE


# SkiROS2 numbers every skill object it makes; `id` is that number (unique in the process).
_skill_ids = itertools.count(1)


class SkillCore:
    """What primitives and compound skills share: a description, a label, parameters, the
    world-model client, a state and the progress counter."""

    # SkiROS2's: False leaves the skill out of the task planner's actions (docs/planning.md),
    # for a skill whose conditions another skill's already cover (the gripper's grasp is
    # Pick without the arm's motion).
    available_for_planning = True

    def __init__(self) -> None:
        self._id = next(_skill_ids)
        self._description: SkillDescription | None = None
        self._label = ""
        self._params = ParamHandler()
        self._wmi: Any = None  # the world-model interface, set by the skill process
        self._state = State.Idle
        self._progress_code = 0
        self._progress_msg = ""
        self._progress_period = 0.0  # s: the average duration of execute()
        self._progress_time = 0.0    # s: since the start
        self._started_at: float | None = None
        self._ticks, self._tick_seconds = 0, 0.0
        self._expand_on_start = False
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
        self._resetParams()

    def _resetParams(self) -> None:
        """The parameters as the description has them (a copy: a run changes only its own)."""
        self._params = ParamHandler(self.description.params.getCopy())

    # -- what a skill reads ---------------------------------------------------------------
    @property
    def params(self) -> ParamHandler:
        return self._params

    @params.setter
    def params(self, ph: ParamHandler) -> None:
        self._params = ph

    @property
    def wmi(self) -> Any:
        return self._wmi

    @wmi.setter
    def wmi(self, wmi: Any) -> None:
        self._wmi = wmi

    @property
    def wm(self) -> Any:
        return self._wmi

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

    @property
    def id(self) -> int:
        """This skill object's number, unique in the process (SkiROS2's)."""
        return self._id

    @property
    def expand_on_start(self) -> bool:
        """SkiROS2: expand again at every start. skillbus always does (the manager asks for
        the tree each time the compound starts), whatever this says."""
        return self._expand_on_start

    # -- state ------------------------------------------------------------------------------
    @property
    def state(self) -> State:
        return self._state

    @state.setter
    def state(self, s: State) -> None:
        self._state = s

    def getState(self) -> State:
        return self._state

    def hasState(self, s: State) -> bool:
        return self._state == s

    # -- progress (SkiROS2's counter) -------------------------------------------------------
    def _setProgress(self, msg: Any, code: int | None = None) -> None:
        """Progress message and code; without a code, the previous one plus one."""
        self._progress_code = self._progress_code + 1 if code is None else int(code)
        self._progress_msg = str(msg)
        self._progress_period = self._tick_seconds / self._ticks if self._ticks else 0.0
        self._progress_time = time.monotonic() - self._started_at if self._started_at is not None else 0.0

    def setProgress(self, msg: Any, code: int | None = None) -> None:
        """skillbus's public name for SkiROS2's ``_setProgress`` (SkiROS2 has no setProgress)."""
        self._setProgress(msg, code)

    def startProgress(self, msg: Any = "Start") -> None:
        """skillbus's name for restarting the counter at 0 (SkiROS2 has no startProgress:
        its start() calls ``_setProgress("Start", 0)``)."""
        self._setProgress(msg, 0)

    @property
    def progress_code(self) -> int:
        return self._progress_code

    @property
    def progress_msg(self) -> str:
        return self._progress_msg

    @property
    def progress_period(self) -> float:
        return self._progress_period

    @property
    def progress_time(self) -> float:
        return self._progress_time

    def printProgress(self) -> str:
        return f"[{self._progress_code}] {self._progress_msg}"

    # skillbus's earlier names for the progress message and code.
    @property
    def message(self) -> str:
        return self._progress_msg

    @message.setter
    def message(self, msg: str) -> None:
        self._progress_msg = str(msg)

    @property
    def code(self) -> int:
        return self._progress_code

    @code.setter
    def code(self, code: int) -> None:
        self._progress_code = int(code)

    # -- results: progress and state, returning the state --------------------------------
    def step(self, msg: str = "") -> State:
        """Still running: the progress code goes up by one."""
        return self._result(State.Running, msg)

    def success(self, msg: str = "") -> State:
        """Done: the progress code goes up by one."""
        return self._result(State.Success, msg)

    def fail(self, msg: str, code: int) -> State:
        """Failed, with a negative code (a positive one is negated, as in SkiROS2)."""
        if not isinstance(code, int) or isinstance(code, bool):
            raise TypeError(f"fail(msg, code): code must be an int, got {type(code).__name__}")
        return self._result(State.Failure, msg, -abs(code))

    def startError(self, msg: str, code: int) -> bool:
        """For onStart: fails with `code` and returns False (the start fails)."""
        self.fail(msg, code)
        return False

    def _result(self, state: State, msg: str, code: int | None = None) -> State:
        self._setProgress(msg, code)
        self._state = state
        return state

    # -- lifecycle bookkeeping (the skill process calls these) -----------------------------
    def _begin(self) -> None:
        """Before onStart: the counter and the clocks start again."""
        self._started_at = time.monotonic()
        self._ticks, self._tick_seconds = 0, 0.0
        self._progress_code, self._progress_msg = 0, ""

    def _started(self) -> None:
        """onStart succeeded (SkiROS2: progress "Start", code 0)."""
        self._state = State.Running
        self._setProgress("Start", 0)

    def _count_tick(self, seconds: float) -> None:
        self._ticks += 1
        self._tick_seconds += seconds

    # -- parameters (SkiROS2's helpers) ---------------------------------------------------
    def specifyParam(self, key: str, values: Any) -> None:
        self._params.specify(key, values)

    def specifyParamDefault(self, key: str, values: Any) -> None:
        self._params.specifyDefault(key, values)

    def specifyParams(self, params: ParamHandler, keep_default: bool = True) -> None:
        self._params.specifyParams(params, keep_default)

    def specifyParamsDefault(self, params: ParamHandler) -> None:
        self._params.specifyParamsDefault(params)

    # -- conditions (judged here with the world-model client; the manager judges them too) --
    def hasPreCond(self) -> bool:
        return bool(self.description.preConditions)

    def hasPostCond(self) -> bool:
        return bool(self.description.postConditions)

    def checkPreCond(self, verbose: bool = False) -> list[str]:
        """The keys of the pre-conditions that do not hold ([]: all hold); sets progress -1."""
        return self._check(self.description.preConditions, "pre", -1, verbose)

    def checkHoldCond(self, verbose: bool = False) -> list[str]:
        return self._check(self.description.holdConditions, "hold", -2, verbose)

    def checkPostCond(self, verbose: bool = False) -> list[str]:
        return self._check(self.description.postConditions, "post", None, verbose)

    def _check(self, conditions: list, kind: str, code: int | None, verbose: bool) -> list[str]:
        failed: list[str] = []
        text = ""
        for c in conditions:
            if not c.evaluate(self._params, self._wmi):
                text += f"{c.getDescription()} Check failed. \n"
                if verbose:
                    log.error("%s-condition check failed: %s", kind, c.getDescription())
                failed += [k for k in c.getKeys() if k not in failed]
        if code is not None:
            self._setProgress(text, code)
        return failed


class PrimitiveBase(SkillCore):
    """A skill that acts. Hooks (override what you need): onInit (once, at load; False:
    not loaded), onStart (before the first execute; False: the start fails), execute
    (every tick; must not block), onPreempt (asked to stop; returns a result like
    execute), onEnd (after the last execute), onReset."""

    def __init__(self) -> None:
        super().__init__()
        self.progress = 0.0  # skillbus: a fraction done, 0..1, for the progress display
        self._idle_until_ns = 0

    def idle_until(self, sim_time_s: float) -> None:
        """skillbus (SkiROS2 has no such call): called in execute() before it returns
        Running, the skill's word that until `sim_time_s` (seconds, the clock of its
        ticks: ``skillbus.tick_context.now_s()``) its execute() would return Running and
        change nothing, as long as its parameters stay as they are (only its message
        might say more, e.g. how far it is: the progress keeps the last one meanwhile).
        The manager then skips its execute ticks until then: a skill that waits for a
        trajectory to end costs no tick. A stop, a preemption, a broken hold-condition, a
        changed parameter, the loss of its process and the end of its task reach it at
        once, as always (docs/skills.md, "A primitive that waits"). Good for
        the ticks after this one only: an execute() that runs again says it anew or not at
        all. A time already past changes nothing."""
        why = f"idle_until({sim_time_s!r}): a sim time in seconds, 0 to 9.2e9"
        try:
            t = float(sim_time_s)
        except (TypeError, ValueError):
            raise ValueError(why) from None
        if not (0.0 <= t < 9.2e9):  # (NaN too) int64 nanoseconds, a time of this clock
            raise ValueError(why)
        self._idle_until_ns = int(t * 1e9)

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

    # -- SkiROS2's _updateRoutine ---------------------------------------------------------
    def _element_stamps(self) -> dict[str, datetime]:
        """When each element parameter last changed (taken before a tick)."""
        return {k: p.last_update for k, p in self._params.items() if p.dataTypeIs(Element)}

    def _updateRoutine(self, before: dict[str, datetime]) -> None:
        """After a tick, as SkiROS2: an element parameter the skill set during the tick
        (``self.params["X"].value = e``) goes to the world model, if its first element is
        concrete: each concrete element's changes are written, an abstract one is added
        (and replaced by the added element)."""
        if self._wmi is None:
            return
        for key, p in self._params.items():
            if key not in before or p.last_update == before[key] or not p.values:
                continue
            if p.values[0].isAbstract():
                continue
            values = list(p.values)
            for i, e in enumerate(values):
                if e.isAbstract():
                    values[i] = self._wmi.add_element(e)
                else:
                    self._wmi.write_element_changes(e)
            p._values = values  # (not a change of the skill's: the stamp stays)


class SkillBase(SkillCore):
    """A compound skill: override expand(skill) to describe its tree."""

    def expand(self, skill: SkillWrapper) -> None:
        pass

    def skill(self, stype: str | Processor, slabel: str = "", remap: dict | None = None,
              specify: dict | None = None, preconditions: list | None = None) -> SkillWrapper:
        """A node for the tree: a skill type (SkiROS2's forms "Pick", ":Pick",
        "skiros:Pick" all name Pick) with an implementation label ("" any), or a processor
        (an anonymous group: ``self.skill(ParallelFf())(child1, child2)``). Remaps apply
        first, then `specify`, which names a remapped parameter by its new name (SkiROS2),
        then `preconditions`: conditions of this node only (addPreCondition)."""
        if isinstance(stype, Processor):
            node = self.getNode(stype)
        elif isinstance(stype, str) and stype:
            node = self.getSkill(stype, slabel)
        else:
            raise TypeError(f"self.skill wants a skill type name or a processor, got {stype!r}")
        for k, v in (remap or {}).items():
            node.remap(k, v)
        for k, v in (specify or {}).items():
            node.specifyParamDefault(k, v)
        for c in preconditions or []:
            node.addPreCondition(c)
        return node

    def getSkill(self, ptype: str, plabel: str = "") -> SkillWrapper:
        return SkillWrapper(skill_type(ptype), plabel)

    def getNode(self, processor: Processor) -> SkillWrapper:
        return SkillWrapper(processor=processor)

    def tree(self) -> SkillWrapper:
        """Runs expand() on a fresh root and returns the root (what the manager executes)."""
        root = SkillWrapper(self.type, self.label)
        self.expand(root)
        if root.remaps or root.specified:
            raise ValueError(f"{self.label}.expand(): a remap or specify on the expanded skill itself "
                             f"({root.remaps or root.specified}) is not carried to the manager; put it on its "
                             f"children (or on a group: self.skill(Serial())(...))")
        return root


def skill_type(name: str) -> str:
    """A skill type as SkiROS2 code names it, as skillbus registers it (the description's
    class name): "skiros:Pick" and ":Pick" are Pick."""
    if name.startswith("skiros:"):
        return name[len("skiros:"):]
    return name[1:] if name.startswith(":") else name
