"""The live trees of tasks, kept from the managers' progress and turned into changes.

A skill manager publishes the whole tree of a task after each of its ticks
(``SB_SKILL_PROGRESS``); a watcher that missed messages (a full queue, a late start)
catches up from the manager's ``SKILL.tasks``, which answers the same trees. Both go
through :class:`TaskTrees`, which keeps the latest tree of each task and says what
changed: the nodes whose fields differ, by node id. The console sends those changes to
browsers, ``skillbus run --watch`` prints them; neither reprints a whole tree.

A tree never goes back: an older tick than the one kept, or a running tree after a
final one, changes nothing (a catch-up answer may cross a newer message). A tree of
another incarnation of the manager (a restarted manager numbers its tasks from 1 again)
replaces the one kept, whatever its tick: it is another task.

>>> trees = TaskTrees()
>>> n = lambda i, parent, state, msg="": {"id": i, "parent": parent, "type": f"S{i}", "label": "",
...     "processor": "", "state": state, "message": msg, "code": 0, "progress": 0.0, "params": {}}
>>> c = trees.apply("", {"task": 1, "tick": 1, "state": "Running", "nodes": [n(0, -1, "Running"), n(1, 0, "Running")]})
>>> sorted(c.nodes), c.new
([0, 1], True)
>>> c = trees.apply("", {"task": 1, "tick": 2, "state": "Running", "nodes": [n(0, -1, "Running"), n(1, 0, "Success", "done")]})
>>> sorted(c.nodes), c.nodes[1]["message"], c.new
([1], 'done', False)
>>> trees.apply("", {"task": 1, "tick": 1, "state": "Running", "nodes": []}) is None  # older: ignored
True
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

FINAL_STATES = ("Success", "Failure")


@dataclass
class TaskTree:
    """A task's latest tree as its manager reported it."""
    robot: str
    task: int
    tick: int
    state: str
    nodes: list[dict[str, Any]]
    sim_time_s: float = 0.0
    incarnation: int = 0  # of the manager that reported it (0: not known)

    @property
    def skill(self) -> str:
        return self.nodes[0]["type"] if self.nodes else ""

    @property
    def message(self) -> str:
        return self.nodes[0]["message"] if self.nodes else ""

    @property
    def ended(self) -> bool:
        return self.state in FINAL_STATES

    def summary(self) -> dict[str, Any]:
        return {"robot": self.robot, "task": self.task, "skill": self.skill, "state": self.state,
                "message": self.message, "tick": self.tick, "sim_time_s": self.sim_time_s, "ended": self.ended}


@dataclass
class TreeChange:
    """What one progress changed in a task's tree: the nodes (by id) that are new or
    differ, and how many nodes the tree has now (a tree that shrank drops the rest)."""
    robot: str
    task: int
    tick: int
    state: str
    count: int
    nodes: dict[int, dict[str, Any]] = field(default_factory=dict)
    new: bool = False      # the first tree seen of this task (a page replaces what it shows of that id)
    ended: bool = False    # this change made it Success or Failure

    def as_json(self) -> dict[str, Any]:
        return {"kind": "tree", "robot": self.robot, "task": self.task, "tick": self.tick, "state": self.state,
                "count": self.count, "nodes": [self.nodes[i] for i in sorted(self.nodes)], "new": self.new,
                "ended": self.ended}


class TaskTrees:
    """The latest tree of every task seen, by (robot, task id); at most `keep_finished`
    finished ones are kept (the oldest go first)."""

    def __init__(self, keep_finished: int = 200) -> None:
        self.keep_finished = keep_finished
        self.trees: dict[tuple[str, int], TaskTree] = {}
        self._finished: list[tuple[str, int]] = []

    def get(self, robot: str, task: int) -> TaskTree | None:
        return self.trees.get((robot, task))

    def running(self) -> list[TaskTree]:
        return [t for t in self.trees.values() if not t.ended]

    def apply(self, robot: str, progress: dict[str, Any], incarnation: int = 0) -> TreeChange | None:
        """Takes one progress (skillbus.skill.cli.progress_json) of the manager's
        `incarnation`; the change it makes, or None when it changes nothing (the same tree
        at the same tick, or one older than that kept)."""
        key = (robot, int(progress["task"]))
        tick, state, nodes = int(progress["tick"]), progress["state"], progress["nodes"]
        old = self.trees.get(key)
        if old is not None and old.incarnation != incarnation:
            old = None  # (another task of the same number: the one kept is replaced)
            if key in self._finished:
                self._finished.remove(key)
        if old is not None and (old.ended or tick < old.tick):
            return None
        tree = TaskTree(robot, key[1], tick, state, nodes, float(progress.get("sim_time_s", 0.0)), incarnation)
        self.trees[key] = tree
        if old is None:
            changed = dict(enumerate(nodes))
        else:
            changed = {i: n for i, n in enumerate(nodes) if i >= len(old.nodes) or old.nodes[i] != n}
            # A later tick alone is a change (no nodes): a page shows the task's tick, which
            # moves while every node stays as it was (a primitive idle until later).
            if not changed and len(nodes) == len(old.nodes) and state == old.state and tick == old.tick:
                return None
        if tree.ended:
            self._finished.append(key)
            while len(self._finished) > self.keep_finished:
                self.trees.pop(self._finished.pop(0), None)
        return TreeChange(robot, key[1], tick, state, len(nodes), changed, new=old is None, ended=tree.ended)


def node_path(nodes: list[dict[str, Any]], i: int) -> str:
    """'ClearTable / PickAndPlace / Grasp': the node's name under its ancestors'."""
    names = []
    while 0 <= i < len(nodes):
        n = nodes[i]
        names.append(n["type"] or f"({n['processor']})")
        i = n["parent"]
    return " / ".join(reversed(names))


def change_lines(tree: TaskTree, change: TreeChange) -> list[str]:
    """A change as lines for a terminal: each changed node's path, state and message."""
    out = []
    for i in sorted(change.nodes):
        n = change.nodes[i]
        msg = f": {n['message']}" if n["message"] else ""
        out.append(f"  {node_path(tree.nodes, i)}  {n['state']}{msg}")
    return out
