"""The console's view of a live system: skill managers, their skills and tasks.

Everything here runs on the bus thread (console.bus_worker). Managers are found as
``skillbus skills`` finds them (a probe on ``SB_MANAGERS_PROBE``, answered on
``SB_MANAGERS``), again every few seconds, so a manager that starts later, or restarts,
is picked up. Of each, the console hears the progress channel and keeps every task's
tree (skill.task_tree); browsers get the changes.

Progress is a lossy channel (a full receive queue drops messages): a task not heard of
for CATCH_UP_S is read from its manager (``SKILL.tasks``), and so is every task a
manager knows when the console first meets it, so tasks started elsewhere, before the
console, appear with their current trees, and no task is left showing a state that is
not its last.
"""

from __future__ import annotations

import logging
import struct
import time
from typing import Any, Callable

from skillbus.channels import robot_channel, valid_robot_name
from skillbus.msgs import (decode, skill_list_t, skill_manager_info_t, skill_progress_list_t, skill_progress_t,
                           skill_start_t, skill_task_t)
from skillbus.rpc import RpcClient, RpcError, RpcTimeout
from skillbus.skill.cli import parse_param, progress_json, skills_json
from skillbus.skill.task_tree import TaskTrees

log = logging.getLogger("skillbus.console")

CATCH_UP_S = 1.0        # a running task not heard of this long is read from its manager
FLUSH_PERIOD_S = 0.05   # trees are updated (and changes sent) at most this often per task
PROBE_PERIOD_S = 3.0    # managers are looked for again this often
MANAGER_CATCH_UP_S = 5.0  # a manager's tasks are read when it is met; an unanswered read is tried again after this
MAX_MANAGERS = 64       # robots followed at once (announcements are bounded, forged or not)
MANAGER_TIMEOUT_S = 2.0
# A manager that has answered none of this many probes in a row is dropped, its running
# tasks lost (counted, not timed: a bus thread held by a long job must not drop them all).
PROBES_UNANSWERED = 3
MANAGER_GONE_S = PROBES_UNANSWERED * PROBE_PERIOD_S  # (what that is, at least, in seconds)
VERBS = ("pause", "step", "resume", "stop")


def task_of(data: bytes) -> int | None:
    """The task id of an encoded skill_progress_t, read without decoding the tree: after
    the fingerprint, header_t (frame, sim time, sender, seq), then the task (LCM: big
    endian, a string as u32 length with its NUL, then the bytes).

    >>> from skillbus.msgs import skill_progress_t
    >>> p = skill_progress_t(); p.task = 42; p.header.sender = "skill_mgr"
    >>> task_of(p.encode()), task_of(b"short")
    (42, None)
    """
    try:
        (n,) = struct.unpack_from(">I", data, 24)
        (task,) = struct.unpack_from(">q", data, 28 + n + 4)
    except struct.error:
        return None
    if data[:8] != skill_progress_t._get_packed_fingerprint():
        return None
    return task


class ConsoleError(RuntimeError):
    """A request the console cannot do; the message is for the user (HTTP 400)."""


class ConsoleTimeout(ConsoleError):
    """A server did not answer in time: what was asked may have been done or not (HTTP
    504); the message says to look before asking again."""


def text_field(req: dict[str, Any], key: str, default: str | None = None) -> str:
    """A text field of an edit: a string; missing, the default (none: it is needed). Any
    other value is refused (str() made a null "None" and a missing label an erased one)."""
    if key not in req:
        if default is None:
            raise ConsoleError(f"this edit needs {key!r} (a string)")
        return default
    value = req[key]
    if not isinstance(value, str):
        raise ConsoleError(f"{key!r} must be a string, not {json_type(value)}")
    return value


def json_type(value: Any) -> str:
    return "null" if value is None else {bool: "a boolean", int: "a number", float: "a number", list: "a list",
                                         dict: "an object"}.get(type(value), type(value).__name__)


class Manager:
    def __init__(self, bus, info: skill_manager_info_t, on_progress: Callable[[str, bytes], None]) -> None:
        self.robot, self.name, self.agent = info.robot, info.name, info.agent
        self.incarnation = info.incarnation
        self.rpc = RpcClient(bus, "SKILL", "console", robot=info.robot)
        self.sub = bus.subscribe(robot_channel("SB_SKILL_PROGRESS", info.robot), on_progress)
        self.unanswered = 0  # probes sent since it was last heard
        self.caught_up, self.catch_up_tried = False, 0.0  # its tasks read (SKILL.tasks)

    def call(self, method: str, req, reply_type, timeout: float = MANAGER_TIMEOUT_S):
        try:
            return self.rpc.call(method, req, reply_type, timeout=timeout)
        except RpcTimeout:
            raise ConsoleTimeout(f"the skill manager of robot {self.robot or '(none)'} did not answer "
                                 f"SKILL.{method} within {timeout:g} s: whether it did it is unknown (look at its "
                                 f"tasks before asking again)") from None


class LiveSkills:
    def __init__(self, bus, emit: Callable[[dict[str, Any]], None]) -> None:
        self.bus, self._emit = bus, emit
        self.seq = 0  # events emitted: a snapshot says which it holds
        self.managers: dict[str, Manager] = {}
        self.trees = TaskTrees()
        self._heard: dict[tuple[str, int], float] = {}
        self._pending: dict[tuple[str, int], tuple[bytes, int]] = {}
        self._flushed = 0.0
        self.refused = 0  # manager announcements not followed (a bad robot name, too many)
        # The incarnation each robot's manager was last heard as (kept after it is dropped):
        # task ids start again at 1 in a restarted manager, so its trees are forgotten then.
        self._incarnations: dict[str, int] = {}
        bus.subscribe(robot_channel("SB_MANAGERS", ""), self._on_manager)

    # -- managers -----------------------------------------------------------
    def probe(self) -> None:
        """Asks every manager to say itself (answers arrive in _on_manager)."""
        m = skill_manager_info_t()
        m.header.frame, m.header.sender = -1, "console"
        self.drop_silent_managers()  # (those that answered none of the probes before this one)
        for known in self.managers.values():
            known.unanswered += 1
        self.bus.publish(robot_channel("SB_MANAGERS_PROBE", ""), m.encode())

    def _on_manager(self, ch: str, data: bytes) -> None:
        info = decode(skill_manager_info_t, data)
        if info is None or info.header.sender == "console":
            return
        if info.robot and not valid_robot_name(info.robot):
            self.refused += 1  # (a name no channel can carry: nothing to call)
            return
        known = self.managers.get(info.robot)
        if known is None and len(self.managers) >= MAX_MANAGERS:
            self.refused += 1
            return
        if known is not None and known.incarnation == info.incarnation and known.name == info.name:
            known.unanswered = 0
            known.agent = info.agent or known.agent
            return
        if known is not None:
            self._drop(known)
        before = self._incarnations.get(info.robot)
        log.info("skill manager %s of robot %s: incarnation %d%s", info.name, info.robot or "(none)", info.incarnation,
                 "" if before is None else f" (before: {before})")
        if before is not None and before != info.incarnation:  # (its tasks are gone with it)
            self._lose_running(info.robot, f"its skill manager started again (incarnation {before} -> "
                                           f"{info.incarnation}) and no longer knows it")
        self._incarnations[info.robot] = info.incarnation
        self.managers[info.robot] = Manager(self.bus, info, lambda c, d, r=info.robot: self._on_progress(r, d))
        self.emit({"kind": "managers", "managers": self.manager_list()})
        # Its running tasks and recent history are read by the next chore, not here: a call
        # waits, and announcements (true or forged) must not hold the bus thread each time.

    def _drop(self, m: Manager) -> None:
        """Stops following a manager (replaced or gone): its subscriptions end."""
        self.bus.unsubscribe(m.sub)
        m.rpc.close()

    def drop_silent_managers(self) -> None:
        """A manager that answered none of the last PROBES_UNANSWERED probes and sent no
        progress meanwhile (killed, its machine gone) is no longer listed and its running
        tasks end as lost; its finished ones stay shown. (Called by probe().)"""
        for robot, m in list(self.managers.items()):
            if m.unanswered >= PROBES_UNANSWERED:
                del self.managers[robot]
                self._drop(m)
                lost = self._lose_running(robot, f"its skill manager has not answered for {MANAGER_GONE_S:g} s "
                                                 f"({PROBES_UNANSWERED} probes)")
                for tree in lost:  # (should it answer again, as the same incarnation: their trees are taken anew)
                    tree.incarnation = -1
                self.emit({"kind": "managers", "managers": self.manager_list()})

    def _lose_running(self, robot: str, why: str) -> list:
        """Every running task of the robot ends as lost (`why`); their trees now."""
        tasks = [t.task for t in self.trees.running() if t.robot == robot]
        for task in tasks:
            self._lost(robot, task, why)
        return [self.trees.get(robot, task) for task in tasks if self.trees.get(robot, task) is not None]

    def manager_list(self) -> list[dict[str, Any]]:
        return [{"robot": m.robot, "name": m.name, "agent": m.agent, "incarnation": m.incarnation}
                for _, m in sorted(self.managers.items())]

    def manager(self, robot: str) -> Manager:
        m = self.managers.get(robot)
        if m is None:
            have = ", ".join(r or "(none)" for r in sorted(self.managers)) or "none"
            raise ConsoleError(f"no skill manager of robot {robot or '(none)'} (managers heard: {have})")
        return m

    # -- tasks --------------------------------------------------------------
    def _on_progress(self, robot: str, data: bytes) -> None:
        # Kept undecoded, the latest per task, until flush(): a manager publishes a tree
        # after every tick, many times faster than a page can show or a person read.
        task = task_of(data)
        if task is None:
            return
        self._heard[(robot, task)] = time.monotonic()
        if (m := self.managers.get(robot)) is not None:
            m.unanswered = 0  # (its progress says it is there, whatever became of the probes' answers)
        # (with the manager's incarnation as of now: one that restarts before the flush must
        # not have its predecessor's last trees taken for its own)
        self._pending[(robot, task)] = (data, self._incarnations.get(robot, 0))

    def flush(self, idle_period_s: float | None = None) -> None:
        """Chore (every FLUSH_PERIOD_S, and before a snapshot): the latest progress heard
        of each task into its tree; the changes to browsers. With `idle_period_s` (no page
        open) only that often."""
        now = time.monotonic()
        if idle_period_s is not None and now - self._flushed < idle_period_s:
            return
        self._flushed = now
        pending, self._pending = self._pending, {}
        for (robot, _task), (data, incarnation) in sorted(pending.items()):
            p = decode(skill_progress_t, data)
            if p is not None:
                self._take(robot, p, incarnation)

    def _take(self, robot: str, p: skill_progress_t, incarnation: int | None = None) -> None:
        self._heard[(robot, p.task)] = time.monotonic()
        change = self.trees.apply(robot, progress_json(p), self._incarnations.get(robot, 0) if incarnation is None
                                  else incarnation)
        if change is not None:
            self.emit(change.as_json())

    def _catch_up(self, robot: str, task: int) -> bool:
        """Reads the manager's latest trees: of `task`, or (0) of every task it knows;
        whether it answered."""
        m = self.managers.get(robot)
        if m is None:
            return False
        req = skill_start_t()
        req.task = task
        try:
            reply = m.call("tasks", req, skill_progress_list_t, timeout=1.0)
        except (ConsoleError, RpcError) as e:
            if task and "no task" in str(e):
                self._lost(robot, task, f"its manager no longer knows it ({e})")
            else:
                log.info("catching up with robot %s: %s", robot or "(none)", e)
            return False
        for p in reply.tasks:
            self._take(robot, p)
        return True

    def _lost(self, robot: str, task: int, why: str) -> None:
        tree = self.trees.get(robot, task)
        if tree is None or tree.ended:
            return
        nodes = [dict(tree.nodes[0], state="Failure", message=why)] if tree.nodes else []
        change = self.trees.apply(robot, {"task": task, "tick": tree.tick, "state": "Failure", "nodes": nodes,
                                          "sim_time_s": tree.sim_time_s}, tree.incarnation)
        if change is not None:
            self.emit(dict(change.as_json(), lost=True))

    def catch_up_quiet_tasks(self) -> None:
        """Chore: a manager met since the last chore has every task it knows read (at most
        one such read per manager every MANAGER_CATCH_UP_S); each running task not heard of
        for CATCH_UP_S is read from its manager."""
        now = time.monotonic()
        for robot, m in list(self.managers.items()):
            if not m.caught_up and now - m.catch_up_tried > MANAGER_CATCH_UP_S:
                m.catch_up_tried = now
                m.caught_up = self._catch_up(robot, 0)
        for tree in self.trees.running():
            key = (tree.robot, tree.task)
            if now - self._heard.get(key, 0.0) > CATCH_UP_S:
                self._heard[key] = now
                self._catch_up(tree.robot, tree.task)

    def emit(self, event: dict[str, Any]) -> None:
        self.seq += 1
        self._emit(dict(event, seq=self.seq))

    def snapshot(self) -> dict[str, Any]:
        """What a browser sees first: the managers and every task's tree, as of event seq."""
        self.flush()
        return {"kind": "hello", "seq": self.seq, "managers": self.manager_list(), "tasks": self.tasks()}

    def tasks(self) -> list[dict[str, Any]]:
        """Every task kept: its summary and whole tree (a browser's first view)."""
        self.flush()
        return [dict(t.summary(), nodes=t.nodes) for _, t in sorted(self.trees.trees.items())]

    # -- skills and commands ------------------------------------------------
    def skills(self) -> list[dict[str, Any]]:
        """Every manager's skills; a manager that does not answer is one entry with its
        `error` (the others' skills are still listed)."""
        out = []
        for robot, m in sorted(self.managers.items()):
            try:
                lst = m.call("list", skill_start_t(), skill_list_t)
            except (ConsoleError, RpcError) as e:
                out.append({"robot": robot, "manager": m.name, "error": str(e)})
                continue
            out += [dict(s, robot=robot, manager=m.name) for s in skills_json(lst)]
        return out

    def start(self, robot: str, skill: str, label: str, params: dict[str, str]) -> int:
        """Starts a skill with text parameters (typed and checked by the manager, as
        `skillbus run -p` does); the task id."""
        m = self.manager(robot)
        req = skill_start_t()
        req.type, req.label = skill, label
        try:
            req.params = [parse_param(f"{k}={v}") for k, v in params.items()]
        except ValueError as e:
            raise ConsoleError(str(e)) from None
        req.num_params = len(req.params)
        try:
            task = m.call("start", req, skill_task_t)
        except RpcError as e:
            raise ConsoleError(str(e)) from None
        return task.task

    def command(self, robot: str, task: int, verb: str) -> str:
        if verb not in VERBS:
            raise ConsoleError(f"unknown command {verb!r} (one of {', '.join(VERBS)})")
        m = self.manager(robot)
        req = skill_start_t()
        req.task = task
        try:
            reply = m.call(verb, req, skill_task_t)
        except RpcError as e:
            raise ConsoleError(str(e)) from None
        self._heard[(robot, task)] = 0.0  # the next chore reads its tree
        return reply.message
