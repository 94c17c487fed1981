"""A skill process: loads skill libraries, announces their skills to a skill manager,
and serves the manager's ticks for its primitives and expansions for its compounds.

    skillbus skills-process --name arm --library my_skills.arm --library my_skills.gripper

Channels: RPC `SB_SKPROC_<NAME>_REQ/REP` (methods tick, expand); calls SKILL.register.
Under lockstep it is a participant (its world-model replica follows the frames).
"""

from __future__ import annotations

import contextlib
import importlib
import inspect
import json
import logging
import os
import re
import struct
import sys
import threading
import time
import traceback
from typing import Any

from skillbus import startup_heap
from skillbus.bus import Bus, open_bus
from skillbus.msgs import skill_register_t, skill_tick_reply_t, skill_tick_t, skill_tree_t, skill_value_t
from skillbus.skill.tick_decode import TickDecoder
from skillbus.skill.tick_wire import TickReply
from skillbus.rpc import RpcBadRequest, RpcClient, RpcDefer, RpcError, RpcServer, reply_channel, request_channel
from skillbus.channels import expand_area
from skillbus.waiting import WaitTimeout, wait_until
from skillbus import tick_context as context
from skillbus.robot import interfaces
from skillbus.skill.convert import apply_param_msgs, description_msg, tree_msg
from skillbus.skill import warm_up
from skillbus.skill.skill import PrimitiveBase, SkillBase, SkillCore, State
from skillbus.validate import BadValue, Rejects, finite, integer, one_of
from skillbus.world.convert import check_element_msg

log = logging.getLogger("skills-process")
# How long a skill process under lockstep waits for its libraries' warm-ups before joining
# (the planner's import: 2.5 s idle, several under load; the demo's master waits 60 s for
# joins, a master's default 10 s).
WARM_UP_TIMEOUT_S = 20.0
TICK_ACTIONS = (skill_tick_t.START, skill_tick_t.EXECUTE, skill_tick_t.PREEMPT, skill_tick_t.END)
VALUE_TYPES = (skill_value_t.STRING, skill_value_t.INT, skill_value_t.FLOAT, skill_value_t.BOOL, skill_value_t.ELEMENT,
               skill_value_t.JSON)


def _no_constant(name: str):
    """json.loads' parse_constant: NaN and Infinity are not JSON, only Python's json takes them."""
    def reject(const: str):
        raise BadValue(name, const, "not a finite number")
    return reject


def check_tick(t: skill_tick_t, actions=TICK_ACTIONS, params: bool = True) -> None:
    """Raises BadValue unless the manager's tick (or expand request) `t` is one to act on:
    a frame of -1 (wall clock) or later and a sim time not before 0 (skills take it as
    "now", the gripper's CAN sends are held until frame + 1), a known action, and
    parameter values a skill can use: a known value type, finite FLOATs (also inside JSON
    lists and dicts and element properties), JSON that parses (`params` False: they were
    checked before, the same bytes: skillbus.skill.tick_decode)."""
    integer(t.frame, "frame", -1)
    integer(t.sim_time_ns, "sim_time_ns", 0)
    one_of(t.action, "action", actions)
    if params:
        check_params(t)


def check_params(t: skill_tick_t) -> None:
    """The parameter values of `check_tick`."""
    for p in t.params:
        for i, v in enumerate(p.values):
            name = f"params.{p.key}[{i}]"
            one_of(v.type, f"{name}.type", VALUE_TYPES)
            if v.type == skill_value_t.FLOAT:
                finite(v.f, name)
            elif v.type == skill_value_t.JSON:
                try:
                    json.loads(v.s, parse_constant=_no_constant(name))
                except json.JSONDecodeError as e:
                    raise BadValue(name, v.s, f"not JSON ({e.msg})") from None
            elif v.type == skill_value_t.ELEMENT:
                check_element_msg(v.element, name, need_id=False)  # (an abstract element has no id yet)


def load_libraries(modules: list[str], wmi: Any = None) -> tuple[dict[str, SkillCore], list[str]]:
    """Imports each module and makes one instance of each skill class it defines (with the
    world-model client, then onInit for a primitive), to check it. Returns those instances
    by label, and the errors (each naming its library or skill); a library or skill that
    fails is left out and the rest still load."""
    found: dict[str, SkillCore] = {}
    errors: list[str] = []
    for mod_name in modules:
        try:
            mod = importlib.import_module(mod_name)
        except Exception as e:
            errors.append(f"library {mod_name}: {type(e).__name__}: {e}")
            continue
        for name, cls in inspect.getmembers(mod, inspect.isclass):
            if cls.__module__ != mod.__name__ or not issubclass(cls, (PrimitiveBase, SkillBase)):
                continue
            if name.startswith("_"):
                continue  # a private base class that skills of the library build on
            try:
                skill = cls()
                skill.wmi = wmi
                if isinstance(skill, PrimitiveBase) and skill.onInit() is False:
                    raise RuntimeError("onInit() returned False")
            except Exception as e:
                errors.append(f"skill {mod_name}.{name}: {type(e).__name__}: {e}")
                continue
            if skill.label in found:
                errors.append(f"skill {mod_name}.{name}: label {skill.label!r} is taken by another skill")
                continue
            found[skill.label] = skill
    return found, errors


class _RetryDeferred:
    """After each of the process's frames: the ticks it deferred until then. With none
    deferred it is idle, and keeps no frame from the quiet-frame core."""

    def __init__(self, server: RpcServer) -> None:
        self.server = server

    def __call__(self, frame: int) -> None:
        self.server.retry_deferred()

    def idle(self) -> bool:
        return not self.server.deferred


class SkillProcess:
    def __init__(self, bus: Bus, name: str, libraries: list[str], wmi: Any = None, participant: Any = None) -> None:
        self.bus, self.name, self.wmi, self.participant = bus, name, wmi, participant
        # The skills as loaded: one instance of each, by label. A compound's expand() runs
        # on its instance (it lives as long as the process: what it keys by id(self) or
        # self.id stays its own); each run of a primitive gets an instance of its own.
        self.loaded, self.errors = load_libraries(libraries, wmi)
        self.classes: dict[str, type] = {label: type(s) for label, s in self.loaded.items()}
        # What the manager has registered, for compounds that plan (TaskPlan): every skill
        # process's skills, this one's when the manager does not answer.
        self.own_descriptions = [description_msg(s) for _, s in sorted(self.loaded.items())]
        self._manager_client: RpcClient | None = None
        # On the wall clock, Liveness sets this: a context in which heartbeats go on from a
        # thread of their own (an expansion that plans may take seconds; the manager drops
        # the skills of a process silent for 3 s).
        self.busy: Any = None
        for s in self.loaded.values():
            s.registered_skills = self.registered_skills
        for e in self.errors:
            log.error("%s", e)
        self.area = "SKPROC_" + name.upper()
        self.instances: dict[int, PrimitiveBase] = {}
        self.server = RpcServer(bus, self.area)
        self._ticks = TickDecoder()
        self.server.add_raw_method("tick", self._tick_raw)
        self.server.add_method("expand", self.on_expand, skill_tick_t, skill_tree_t)
        for method in ("tick", "expand"):  # defer before decoding: a tick is decoded once
            self.server.methods[method] = self._frame_gate(self.server.methods[method])
        # The same expansion for anyone holding the bus key (`skillbus tree SKILL`): the
        # process's own area is the manager's alone under the system's policy (only it
        # ticks skills), so an operator's request there was dropped and waited out its
        # timeout. An expansion acts on nothing; what it reads is the world as it is.
        # (not served where the policy lets it send no answer: an older policy file without the
        # SB_SKTREE rules; every answer would be refused, each request logged as a failure)
        refused = bus.refused(reply_channel(expand_area(self.name))) if hasattr(bus, "refused") else ""
        self.expansions: RpcServer | None = None
        if refused:
            log.warning("expansions for operators (skillbus tree) not served: %s", refused)
        else:
            self.expansions = RpcServer(bus, expand_area(self.name))  # (SB_SKTREE_<NAME>_REQ)
            self.expansions.add_method("expand", self.on_expand, skill_tick_t, skill_tree_t)
        if participant is not None:
            # A tick of frame n is answered only after this process has finished its own
            # frame n, so the skill always sees the world-model replica and the devices as
            # they were at the end of frame n, however the tick and the clock raced.
            participant.after_frame.append(_RetryDeferred(self.server))
        self.incarnation = time.time_ns()  # identity of this run of the process, not behaviour
        self.rejects = Rejects(f"skills-process {name}")  # ticks and expansions refused (check_tick)

    def registered_skills(self) -> list:
        """The skill descriptions the skill manager has registered (skill_description_t, all
        processes'); this process's own when it does not answer within 5 s (no manager:
        --standalone)."""
        from skillbus.msgs import skill_list_t, skill_start_t
        if self._manager_client is None:
            self._manager_client = RpcClient(self.bus, "SKILL", f"{self.name}-planner")
        try:
            return list(self._manager_client.call("list", skill_start_t(), skill_list_t, timeout=5.0).skills)
        except RpcError as e:
            log.warning("the skill manager did not list its skills (%s): planning with this process's own", e)
            return list(self.own_descriptions)

    def registration(self) -> skill_register_t:
        m = skill_register_t()
        m.process, m.rpc_area, m.incarnation = self.name, self.area, self.incarnation
        m.skills = [description_msg(skill) for _, skill in sorted(self.loaded.items())]
        m.num_skills = len(m.skills)
        m.errors, m.num_errors = list(self.errors), len(self.errors)
        return m

    def check_processors(self, client: RpcClient, timeout: float = 2.0) -> list[str]:
        """The processor classes (skillbus.skill.processors and the libraries' own) that the
        manager's tree engine does not know: a tree naming one would fail at expansion."""
        from skillbus.msgs import skill_processors_t, skill_start_t
        from skillbus.skill.processors import all_processors
        known = client.call("processors", skill_start_t(), skill_processors_t, timeout=timeout)
        names = set(known.names)
        return [f"processor {name} ({cls.__module__}) is not known to the skill manager "
                f"(it knows: {', '.join(sorted(names))})"
                for name, cls in sorted(all_processors().items()) if name not in names]

    def register(self, timeout: float = 30.0) -> skill_register_t:
        """Announces the skills to the manager; retries until it answers. Raises
        WaitTimeout (naming the manager's channel and the last error) after `timeout`."""
        client = RpcClient(self.bus, "SKILL", self.name)
        deadline = time.monotonic() + timeout

        def left() -> float:  # each call within what is left of `timeout` (a 2 s call outlasted a shorter one)
            return min(2.0, max(0.05, deadline - time.monotonic()))

        def attempt() -> skill_register_t:
            for e in self.check_processors(client, left()):
                if e not in self.errors:
                    log.error("%s", e)
                    self.errors.append(e)
            return client.call("register", self.registration(), skill_register_t, timeout=left())

        try:
            reply = wait_until(attempt, timeout, f"registration with the skill manager on {request_channel('SKILL')}",
                               interval=0.0, retry_on=(RpcError,))
        finally:
            # Registered again whenever the manager's announcement does not list this process
            # (forged announcements too): a client left subscribed each time would pile up.
            client.close()
        for e in reply.errors:
            log.error("the manager refused: %s", e)
        return reply

    # -- RPC methods ------------------------------------------------------------
    def _reply(self, skill: SkillCore | None, state: State, message: str, code: int = 0) -> skill_tick_reply_t:
        # Every tick sends one: skillbus.skill.tick_wire encodes the skill's parameters
        # straight from its Params (as convert.param_msg and LCM's encoder would).
        r = TickReply.of_params(skill.params.values() if skill is not None else ())
        r.state, r.message, r.code = int(state), message, code
        r.wm_version = self.wmi.version if self.wmi is not None else -1
        if skill is not None:
            r.progress = float(getattr(skill, "progress", 0.0))
            if state == State.Running:
                r.idle_until_ns = getattr(skill, "_idle_until_ns", 0)
        return r

    def _frame_gate(self, method):
        """A tick's frame and sim time are the last 16 bytes of its encoding: a tick that
        comes before this process has finished that frame is deferred undecoded."""
        def gated(payload: bytes) -> bytes:
            if self.participant is not None and len(payload) >= 24:
                frame = struct.unpack(">q", payload[-16:-8])[0]
                if frame >= 0 and self.participant.completed_frame < frame:
                    raise RpcDefer()
            return method(payload)
        return gated

    def _tick_raw(self, payload: bytes) -> bytes:
        """RPC "tick": the request decoded by skillbus.skill.tick_decode (parameters seen
        before are not decoded again), answered by on_tick."""
        decoded = self._ticks.decode(payload)
        if decoded is None:
            raise RpcBadRequest("payload of tick does not decode as skill_tick_t")
        t, params_checked = decoded
        return self.on_tick(t, params_checked, payload).encode()

    def on_tick(self, t: skill_tick_t, params_checked: bool = False, payload: bytes | None = None) -> skill_tick_reply_t:
        try:
            check_tick(t, params=not params_checked)
        except BadValue as e:  # answered (the manager must not wait for it), never run
            self.rejects.record(f"{self.area}.tick", e)
            return self._reply(None, State.Failure, f"skill process {self.name} refused the tick of {t.label!r}: {e}",
                               -1)
        if payload is not None and not params_checked:
            self._ticks.remember(payload, t)  # (sound parameters only)
        with context.ticking(t.frame, t.sim_time_ns):
            return self._tick(t)

    def _tick(self, t: skill_tick_t) -> skill_tick_reply_t:
        r = self._act(t)
        if t.action == skill_tick_t.PREEMPT or (
                t.action in (skill_tick_t.START, skill_tick_t.EXECUTE) and r.state != State.Running):
            self._end(t, r)
        return r

    def _end(self, t: skill_tick_t, r: skill_tick_reply_t) -> None:
        """As SkiROS2 does within the tick that finishes a primitive and right after its
        onPreempt: onEnd, then the instance is forgotten, and the reply says so (the
        manager then sends no END: a round trip less at every primitive's end). The
        reply keeps the tick's state, message and code; its parameters (encoded from the
        skill's Params when it is sent) and world-model version are those after onEnd.
        An exception in onEnd is logged and changes nothing, as it did in an END."""
        skill = self.instances.pop(t.instance, None)
        if skill is not None:
            try:
                skill.onEnd()
            except Exception:
                log.error("%s.onEnd failed:\n%s", t.label, traceback.format_exc())
            if self.wmi is not None:
                r.wm_version = self.wmi.version
        r.ended = True

    def _act(self, t: skill_tick_t) -> skill_tick_reply_t:
        """The tick's action on its instance (END included: a manager sends one where no
        reply said the instance ended, e.g. after a tick this process refused)."""
        cls = self.classes.get(t.label)
        if cls is None or not issubclass(cls, PrimitiveBase):
            return self._reply(None, State.Failure, f"{self.name} has no primitive {t.label!r}", -1)
        skill = self.instances.get(t.instance)
        hook = "onStart"
        try:
            if t.action == skill_tick_t.START:
                skill = cls()
                skill.wmi = self.wmi
                hook = "onInit"  # every instance that runs is initialised (not only the one checked at load)
                if skill.onInit() is False:
                    return self._reply(skill, State.Failure, skill.message or f"{t.label}: onInit() returned False", -1)
                hook = "onStart"
                apply_param_msgs(skill, t.params)
                self.instances[t.instance] = skill
                skill._begin()
                if skill.onStart() is False:  # (None is a start: skillbus skills need not return True)
                    # startError(msg, code) set the message and a negative code
                    return self._reply(skill, State.Failure, skill.message or f"{t.label}: onStart() returned False",
                                       skill.code if skill.code < 0 else -1)
                skill._started()
                hook = "execute"
                state = self._execute(skill)
            elif skill is None:
                return self._reply(None, State.Failure,
                                   f"skill process {self.name} has no running instance {t.instance} of {t.label}: "
                                   f"it was lost (this process was started after the skill was)", -1)
            elif t.action == skill_tick_t.EXECUTE:
                hook = "execute"
                apply_param_msgs(skill, t.params)
                state = self._execute(skill)
            elif t.action == skill_tick_t.PREEMPT:
                hook = "onPreempt"
                state = skill.onPreempt()
            elif t.action == skill_tick_t.END:
                hook = "onEnd"
                skill.onEnd()
                self.instances.pop(t.instance, None)
                return self._reply(skill, skill.state, skill.message, skill.code)
            else:
                return self._reply(skill, State.Failure, f"unknown tick action {t.action}", -1)
            if not isinstance(state, State):
                return self._reply(skill, State.Failure,
                                   f"{t.label}.{hook}() returned {state!r}; return self.step/success/fail(...)", -1)
            skill.state = state
            return self._reply(skill, state, skill.message, skill.code)
        except Exception as e:  # a skill's bug fails the skill, never the process
            log.error("%s.%s failed:\n%s", t.label, hook, traceback.format_exc())
            if t.action == skill_tick_t.END:
                self.instances.pop(t.instance, None)
            # (otherwise _tick ends it: its onEnd runs, as after any failure, to clean up)
            return self._reply(skill, State.Failure, f"{t.label}.{hook}() raised {type(e).__name__}: {e}", -1)

    @staticmethod
    def _execute(skill: PrimitiveBase) -> Any:
        """One execute(), timed for the progress period; then, as SkiROS2's tick, the
        element parameters it set go to the world model (_updateRoutine)."""
        stamps = skill._element_stamps()
        skill._idle_until_ns = 0  # (said anew by each execute() that idles)
        t0 = time.monotonic()
        state = skill.execute()
        skill._count_tick(time.monotonic() - t0)
        if isinstance(state, State):
            skill._updateRoutine(stamps)
        return state

    def on_expand(self, t: skill_tick_t) -> skill_tree_t:
        try:
            check_tick(t, actions=(skill_tick_t.EXPAND,))
        except BadValue as e:
            self.rejects.record(f"{self.area}.expand", e)
            out = skill_tree_t()
            out.error = f"skill process {self.name} refused the expansion of {t.label!r}: {e}"
            return out
        skill = self.loaded.get(t.label)
        if not isinstance(skill, SkillBase):
            out = skill_tree_t()
            out.error = f"{self.name} has no compound skill {t.label!r}"
            return out
        try:
            # The real instance (the one loaded and registered), with the description's
            # parameters again and this run's values.
            skill._resetParams()
            skill.wmi = self.wmi
            apply_param_msgs(skill, t.params)
            if self.busy is None:
                return tree_msg(skill.tree())
            with self.busy():
                return tree_msg(skill.tree())
        except Exception as e:
            out = skill_tree_t()
            out.error = f"{t.label}.expand() raised {type(e).__name__}: {e}"
            return out


def bad_input(proc: SkillProcess, wmi: Any, participant: Any) -> dict[str, Any]:
    """For the process's summary: what it received and did not act on, in total and by
    kind: its ticks, its world-model replica's changes, its interfaces' messages and
    frames (those that count them: `rejects`), the lockstep layer's bad messages."""
    counters = [proc.rejects, getattr(wmi, "rejects", None)]
    counters += [getattr(interfaces.get(name), "rejects", None) for name in sorted(interfaces.configured())]
    kinds: dict[str, int] = {}
    for c in counters:
        if c is not None:
            for kind, n in c.summary().items():
                kinds[kind] = kinds.get(kind, 0) + n
    lockstep = participant.bad_input.total if participant is not None else 0
    return {"bad_input": sum(kinds.values()) + lockstep, "rejected": kinds}


def interface_specs(args) -> list[tuple[str, str, str]]:
    """The interfaces to load, (name, module, arg): the configuration file's [interfaces],
    then --interface NAME=MODULE[:ARG], then the shortcuts --arm and --gripper (a later
    one of the same name wins)."""
    specs: dict[str, tuple[str, str, str]] = {}
    for name, text in (getattr(args, "config_interfaces", None) or {}).items():
        specs[name] = interfaces.parse(f"{name}={text}")
    for text in getattr(args, "interface", None) or []:
        name, module, arg = interfaces.parse(text)
        specs[name] = (name, module, arg)
    if getattr(args, "arm", False):
        specs["arm"] = ("arm", "skillbus.robot.arm", "")
    if getattr(args, "gripper", None):
        specs["gripper"] = ("gripper", "skillbus.can.gripper_service", args.gripper)
    return list(specs.values())


def apply_config(args) -> None:
    """Reads --config (TOML): process settings the command line did not give, and the
    [interfaces] table."""
    import tomllib
    path = getattr(args, "config", None)
    if not path:
        return
    with open(path, "rb") as f:
        conf = tomllib.load(f)
    known = {"name", "library", "world_model", "lockstep", "url", "can_interface", "interfaces"}
    unknown = sorted(set(conf) - known)
    if unknown:
        raise ValueError(f"{path}: unknown setting(s) {', '.join(unknown)} (known: {', '.join(sorted(known))})")
    for key in ("name", "url"):
        if getattr(args, key, None) in (None, "") and key in conf:
            setattr(args, key, conf[key])
    args.library = list(conf.get("library", [])) + list(args.library or [])
    for key in ("world_model", "lockstep"):
        if conf.get(key):
            setattr(args, key, True)
    if "can_interface" in conf and args.can_interface == "skillbus_vcan":
        args.can_interface = conf["can_interface"]
    args.config_interfaces = dict(conf.get("interfaces", {}))


_NAME = re.compile(r"[A-Za-z0-9_]{1,64}")  # (what a DDS topic takes: skillbus.channels.bad_characters)


def name_problem(name: str) -> str:
    """Why `name` cannot name a skill process ("" when it can): the skill manager's rule
    (1 to 64 letters, digits or _) and its RPC channels, which must fit LCM's 63
    bytes with the robot's name in front. Said at start: else the process would register
    and then fail every tick, or be refused by the manager after loading its libraries."""
    if not _NAME.fullmatch(name):
        return "a skill process name is 1 to 64 letters, digits or '_' (it becomes part of channel names)"
    try:
        request_channel("SKPROC_" + name.upper())
        reply_channel("SKPROC_" + name.upper())
    except ValueError as e:
        return str(e)
    return ""


def main(args) -> int:
    sys.path.insert(0, os.getcwd())  # libraries next to where the user runs it
    try:
        apply_config(args)
    except (OSError, ValueError) as e:
        print(f"error: --config: {e}", file=sys.stderr)
        return 2
    if not args.name or not args.library:
        print("error: skills-process needs --name and at least one --library (or both in --config)", file=sys.stderr)
        return 2
    why = name_problem(args.name)
    if why:
        print(f"error: --name {args.name!r}: {why}", file=sys.stderr)
        return 2
    if getattr(args, "standalone", False) and args.lockstep:
        print("error: --standalone serves without a manager on the wall clock; not with --lockstep", file=sys.stderr)
        return 2
    bus = open_bus(args.url)
    # What it will answer on, checked now: under a policy that does not let its identity
    # send there, the manager would drop every answer as forbidden and only say that a
    # tick was not answered (an added process runs as "operator" unless told otherwise).
    from skillbus.bus import channel as bus_channel
    answers = [reply_channel("SKPROC_" + args.name.upper())]
    if not getattr(args, "standalone", False):  # (alone it sends no heartbeats)
        answers.append(bus_channel("SB_LOCKSTEP_ACK" if args.lockstep else "SB_SKILL_HEARTBEAT"))
    for ch in answers:
        why = bus.refused(ch) if hasattr(bus, "refused") else ""
        if why:
            print(f"error: skills-process {args.name}: {why}", file=sys.stderr)
            return 2
    participant = None
    if args.lockstep:
        from skillbus.lockstep import LockstepParticipant
        participant = LockstepParticipant(bus, args.name, kind="skills-process")
    wmi = None
    if args.world_model:
        from skillbus.world import WorldModelInterface
        wmi = WorldModelInterface(bus, args.name, participant=participant)
    try:
        for name, module, arg in interface_specs(args):
            interfaces.load(name, module, arg, bus, participant, can_interface=args.can_interface)
    except Exception as e:  # an interface that cannot start (no gripper answers, a bad module): say which
        print(f"error: {e}", file=sys.stderr)
        return 2
    proc = SkillProcess(bus, args.name, args.library, wmi, participant)
    print(json.dumps({"process": args.name, "skills": sorted(proc.classes), "errors": proc.errors}), flush=True)
    if not proc.loaded and proc.errors:
        # Nothing to serve: running on, it registered no skill, supervisord showed it RUNNING,
        # and `skillbus run` later said only "unknown skill".
        print(f"error: skills-process {args.name}: no skill loaded: {'; '.join(proc.errors)}", file=sys.stderr)
        return 2
    if getattr(args, "standalone", False):
        log.info("serving %d skill(s) without a skill manager (--standalone)", len(proc.classes))
        startup_heap.set_aside()
        while True:
            bus.handle(1.0)
    try:
        reply = proc.register(timeout=args.register_timeout)
    except WaitTimeout as e:
        print(f"error: {e}: is the skill manager running, in this network namespace?", file=sys.stderr)
        return 1
    log.info("registered %d skill(s) with the manager (%d refused)", len(proc.classes), len(reply.errors))
    if participant is not None:
        # A library's warm-up (TaskPlan's planner import) would take a core and the
        # interpreter's lock from every frame it overlaps: done before joining.
        left = warm_up.wait(WARM_UP_TIMEOUT_S)
        if left:
            log.warning("joining lockstep with warm-up %s still running after %.0f s: frames will be slower "
                        "until it ends", ", ".join(left), WARM_UP_TIMEOUT_S)
        # Under lockstep the process follows the frames (its world-model replica changes
        # only at frame boundaries); RPC ticks are answered while it waits for a clock.
        set_aside = startup_heap.set_aside()
        r = participant.run()
        print(json.dumps({"ok": r.ok, "error": r.error, "frames": r.frames, "quiet_frames": participant.quiet_frames,
                          "startup_objects": set_aside,
                          "digest": r.digest_hex, **bad_input(proc, wmi, participant)}), flush=True)
        return 0 if r.ok else 1
    startup_heap.set_aside()
    Liveness(bus, proc, url=args.url).serve_forever()


class Liveness:
    """On the wall clock: a heartbeat to the manager twice a second (a silent process has
    its skills dropped), and a new registration whenever the manager's announcement does
    not list this process (the manager restarted and forgot it)."""

    HEARTBEAT_S = 0.5

    def __init__(self, bus: Bus, proc: "SkillProcess", url: str | None = None) -> None:
        from skillbus.bus import channel
        from skillbus.msgs import skill_alive_t
        self.bus, self.proc, self.url = bus, proc, url
        self.reregister = False
        self._alive_t = skill_alive_t
        self._heartbeat_channel = channel("SB_SKILL_HEARTBEAT")
        self._side_bus: Bus | None = None
        bus.subscribe(channel("SB_SKILL_MANAGER"), self._on_manager)
        proc.busy = self.busy

    @contextlib.contextmanager
    def busy(self):
        """Heartbeats from a thread while the main loop is held up (a long expansion). They
        go on a bus of their own: this process's bus (its sender's counter, its sockets)
        is the main thread's alone."""
        if self._side_bus is None:
            self._side_bus = open_bus(self.url)
        stop = threading.Event()

        def beat() -> None:
            while not stop.wait(self.HEARTBEAT_S):
                self.heartbeat(self._side_bus)

        t = threading.Thread(target=beat, name="heartbeat", daemon=True)
        t.start()
        try:
            yield
        finally:
            stop.set()
            t.join()

    def _on_manager(self, ch: str, data: bytes) -> None:
        from skillbus.msgs import decode
        a = decode(self._alive_t, data)
        if a is not None and self.proc.name not in a.processes:
            self.reregister = True  # not here: an RPC call must not run inside a handler

    def heartbeat(self, bus: Bus | None = None) -> None:
        m = self._alive_t()
        m.header.frame = -1
        m.sender, m.incarnation = self.proc.name, self.proc.incarnation
        (bus or self.bus).publish(self._heartbeat_channel, m.encode())

    def serve_forever(self) -> None:
        next_beat = 0.0
        while True:
            now = time.monotonic()
            if now >= next_beat:
                self.heartbeat()
                next_beat = now + self.HEARTBEAT_S
            if self.reregister:
                self.reregister = False
                try:
                    self.proc.register(timeout=2.0)
                    log.info("registered again: the skill manager did not list this process")
                except WaitTimeout as e:
                    log.warning("registering again failed (%s); will retry at the next announcement", e)
            self.bus.handle(max(0.0, min(self.HEARTBEAT_S, next_beat - time.monotonic())))
