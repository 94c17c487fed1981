"""``ManipSkill``: a manipulation skill in InternDataEngine's style. A subclass builds a
manipulation command list (``self.manip_list``, see skillbus.manip.command) in
``simple_generate_manip_cmds()``; the executor (skillbus.manip.executor) pops one
command at a time: it plans the motion with the motion service, plays it, applies the
command's action, and pops the command once ``is_subtask_done()`` says so. It stops
with a failure when ``is_feasible()`` turns false (too many planning failures); when the
list is empty (``is_done()``) the skill ends, a success if ``is_success()``.

Each registered skill is also a SkiROS2-style skill of the skill manager (its
parameters, conditions, preemption and progress): skillbus.manip.primitive binds it.

    from skillbus.manip import ManipSkill, register_skill

    @register_skill
    class Lift(ManipSkill):
        defaults = {"height": 0.1}

        def simple_generate_manip_cmds(self):
            p, q = self.controller.get_ee_pose()
            self.manip_list = [(p + [0, 0, self.cfg["height"]], q, "dummy_forward", {"motion": "linear"})]

What a skill reads: ``self.controller`` (the end effector's pose in the base frame,
planning failures; skillbus.manip.views.Controller), ``self.task`` (objects, articulated
joints, annotated grasps; skillbus.manip.views.TaskView), ``self.cfg`` (its YAML
configuration merged with the skill's parameters), ``self.robot`` (names of the arm and
gripper elements).
"""

from __future__ import annotations

from typing import Any, ClassVar


# Keys every manipulation skill reads (the executor's and is_feasible's).
COMMON_KEYS = ("command_timeout_s", "speed", "max_plan_failures")


class ManipSkill:
    key: ClassVar[str] = ""          # set by register_skill
    defaults: ClassVar[dict] = {}    # configuration values a YAML file or a parameter may override
    # Element parameters beyond Arm and Gripper: name -> concept (e.g. {"Object": "skiros:Product"})
    elements: ClassVar[dict[str, str]] = {}
    optional_elements: ClassVar[dict[str, str]] = {}
    # Configuration keys it reads beyond `defaults` and its elements (e.g. ("pose",)). A
    # class that declares them (even as ()) is strict: any other key its configuration
    # gives (a typo, `distnce: 0.3`) is refused, naming it, instead of being ignored while
    # the default acts. None (a skill ported as it was): every key is taken.
    options: ClassVar[tuple[str, ...] | None] = None

    @classmethod
    def known_keys(cls) -> list[str]:
        return sorted({*cls.defaults, *cls.elements, *cls.optional_elements, *(cls.options or ()), *COMMON_KEYS})

    @classmethod
    def unknown_keys(cls, cfg: dict) -> list[str]:
        """The keys of `cfg` a strict class does not read (sorted; [] when not strict)."""
        if cls.options is None:
            return []
        known = set(cls.known_keys())
        return sorted(str(k) for k in cfg if k not in known)

    @classmethod
    def keys_refused(cls, cfg: dict) -> str:
        """"" or why `cfg` is refused: the keys a strict class does not read, and the ones it takes."""
        unknown = cls.unknown_keys(cfg)
        return f"unknown key(s) {', '.join(unknown)} (it takes: {', '.join(cls.known_keys())})" if unknown else ""

    def __init__(self, robot: Any, controller: Any, task: Any, cfg: dict) -> None:
        self.robot = robot
        self.controller = controller
        self.task = task
        self.cfg = dict(cfg)
        self.skill_cfg = self.cfg  # InternDataEngine's name for it
        self.manip_list: list = []
        self.plan_flag = False
        self.failure_reason = ""   # set by is_success() (or anything else) to say why it failed

    # -- what a skill defines --------------------------------------------------------
    def simple_generate_manip_cmds(self) -> None:
        raise NotImplementedError(f"{type(self).__name__} must build self.manip_list in simple_generate_manip_cmds()")

    @classmethod
    def describe(cls, description: Any) -> None:
        """Adds conditions to the skill manager's description (SkiROS2's calls:
        ``description.addPreCondition(...)``); parameters come from `elements`,
        `optional_elements` and `defaults`."""

    def is_ready(self) -> bool:
        return True

    def update(self) -> None:
        """Called on every tick before the head command is driven (a skill may extend or
        regenerate manip_list here)."""

    def is_feasible(self, th: int | None = None) -> bool:
        limit = self.cfg.get("max_plan_failures", 3) if th is None else th
        return self.controller.num_plan_failed <= limit

    def is_subtask_done(self) -> bool:
        """Whether the head command is done: by default when its motion has settled and its
        action has finished."""
        return self.controller.head_finished

    def is_done(self) -> bool:
        if not self.manip_list:
            return True
        if self.is_subtask_done():
            self.manip_list.pop(0)
        return not self.manip_list

    def is_success(self) -> bool:
        return True

    def world_ops(self) -> list:
        """World-model writes that make the world model say what the skill did (a pick: the
        gripper contains the object), written once on success; the primitive finishes when
        ``world_shows()`` says its replica shows them."""
        return []

    def world_shows(self) -> bool:
        return True

    def is_record(self) -> bool:
        return True
