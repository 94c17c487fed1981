"""SkillWrapper: a node of the tree a compound skill's expand() describes (SkiROS2's
SkillWrapper and its generic Skill node, for what a tree needs): a placeholder for a skill
type, resolved to an implementation when the tree starts, or an anonymous group under a
processor. Calling it adds children: ``node(child1, child2)``.

The skill manager executes the tree; a node carries to it its type and label, its
processor, its remaps (the child's key -> the key one level up), its fixed values and
conditions of its own (checked with the skill's, in the skill's own keys).

    >>> n = SkillWrapper("Pick", "", remap={"Object": "Target"}, specify={"Target": "cube"})
    >>> n.remaps, n.specified    # specify names the key after the remap, as in SkiROS2
    ({'Object': 'Target'}, {'Object': 'cube'})
"""

from __future__ import annotations

import copy
import logging
from typing import Any

from skillbus.skill.processors import Processor, SerialStar

log = logging.getLogger("skillbus.skill")

NO_LATCH = ("the skill manager does not copy a sibling's post-conditions (SkiROS2's latch): add them to the node "
            "with addPreCondition, or to the skill's description")


class SkillWrapper:
    def __init__(self, type_: str = "", label: str = "", remap: dict | None = None,
                 specify: dict | None = None, processor: Processor | None = None) -> None:
        self.type, self.label = type_, label
        self._remaps: dict[str, str] = {}
        self._specify: dict[str, Any] = {}
        self.processor: Processor = processor or SerialStar()  # SkiROS2's default (its code, not its wiki)
        self.children: list[SkillWrapper] = []
        self._parent: SkillWrapper | None = None
        self.conditions: dict[str, list] = {"pre": [], "hold": [], "post": []}  # the node's own, in its own keys
        for k, v in (remap or {}).items():
            self.remap(k, v)
        for k, v in (specify or {}).items():
            self.specifyParamDefault(k, v)

    # -- parameters --------------------------------------------------------------------
    @property
    def remaps(self) -> dict[str, str]:
        """The node's remaps: its own key -> the key one level up."""
        return dict(self._remaps)

    @property
    def specified(self) -> dict[str, Any]:
        """The values fixed for the node, by its own keys."""
        return dict(self._specify)

    def remap(self, initial_key: str, target_key: str, record: bool = True) -> None:
        """The node's parameter `initial_key` reads and writes `target_key` one level up (a
        group's remap holds for everything under it). As in SkiROS2, a second remap of the
        same key is ignored (with a warning if it differs) and one onto a key that is
        itself remapped follows it (1->2 with 2->3 gives 1->3)."""
        if initial_key in self._remaps:
            if self._remaps[initial_key] != target_key:
                log.warning("remap %s -> %s ignored: %s is already remapped to %s", initial_key, target_key,
                            initial_key, self._remaps[initial_key])
            return
        self._remaps[initial_key] = self._remaps.get(target_key, target_key)

    def get_remap(self, key: str) -> str:
        return self._remaps.get(key, key)

    def _own_key(self, key: str) -> str:
        """SkiROS2 renames a parameter when it remaps it, so its code names a remapped
        parameter by the new name; the manager wants the node's own key."""
        for own, target in self._remaps.items():
            if target == key:
                return own
        return key

    def specifyParamDefault(self, key: str, value: Any) -> None:
        """Fixes the parameter's value for this node (the blackboard does not override it);
        a remapped parameter is named by its new name, as in SkiROS2."""
        self._specify[self._own_key(key)] = value

    specifyParam = specifyParamDefault  # (SkiROS2's differ only in keeping it as the default)

    def _add_condition(self, kind: str, condition: Any) -> None:
        """A condition of this node only (the skill's description keeps its own). Its keys
        name the skill's parameters, by their own names or, as SkiROS2 code does after a
        remap, by the remapped names; the manager checks it with the skill's conditions."""
        from skillbus.skill.conditions import ConditionBase
        if not self.type:
            raise NotImplementedError(f"a {kind}-condition on a group ({self.processor.spec()}): only a skill node "
                                      f"carries conditions of its own; put it on the skills under the group")
        if not isinstance(condition, ConditionBase):
            raise TypeError(f"a {kind}-condition must be a condition (ConditionProperty, ...), got {condition!r}")
        own = copy.deepcopy(condition)
        for key, target in self._remaps.items():
            if key != target:
                own.remap(target, key)
        self.conditions[kind].append(own)

    def addPreCondition(self, condition: Any, modify_description: bool = False) -> None:
        """A pre-condition of this node (`modify_description` has no meaning here: the
        description belongs to the skill's process)."""
        self._add_condition("pre", condition)

    def addHoldCondition(self, condition: Any, modify_description: bool = False) -> None:
        self._add_condition("hold", condition)

    def addPostCondition(self, condition: Any, modify_description: bool = False) -> None:
        self._add_condition("post", condition)

    # -- structure ---------------------------------------------------------------------
    def setProcessor(self, processor: Processor) -> None:
        if not isinstance(processor, Processor):
            raise TypeError(f"setProcessor wants a processor (Serial(), SerialStar(), ...), got {processor!r}")
        self.processor = processor

    def addChild(self, child: "SkillWrapper", latch: bool = False) -> "SkillWrapper":
        if latch:
            raise NotImplementedError(f"addChild(latch=True) (the previous child's post-conditions as pre-conditions): "
                                      f"{NO_LATCH}")
        if not isinstance(child, SkillWrapper):
            raise TypeError(f"a child of {self.type or self.processor.spec()} must come from self.skill(...), "
                            f"got {child!r}")
        child._parent = self
        self.children.append(child)
        return self

    def __call__(self, *children: "SkillWrapper") -> "SkillWrapper":
        for c in children:
            self.addChild(c)
        return self

    node = __call__

    @property
    def parent(self) -> "SkillWrapper | None":
        return self._parent

    def getParent(self) -> "SkillWrapper | None":
        return self._parent

    def hasChildren(self) -> bool:
        return bool(self.children)

    def last(self) -> "SkillWrapper":
        return self.children[-1]

    def popChild(self) -> "SkillWrapper":
        child = self.children.pop()
        child._parent = None
        return child

    def describe(self) -> dict:
        """The tree as plain data, for the skill manager."""
        return {"type": self.type, "label": self.label, "processor": self.processor.spec(),
                "remap": dict(self._remaps), "specify": {k: _plain(v) for k, v in self._specify.items()},
                "children": [c.describe() for c in self.children]}


def _plain(v: Any) -> Any:
    from skillbus.world.element import Element
    if isinstance(v, Element):
        return {"element": v.id or v.type, "label": v.label}
    return copy.deepcopy(v)
