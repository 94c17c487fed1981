"""Fuzzed bus messages for the fuzz test (test_fuzz.py, through fuzz_publisher.py): for a
list of channels, each with its message type (or, for an RPC channel, its methods and
their request types), message number i of a seed is always the same bytes, so a failure
is replayed from (seed, i) alone (``fuzz_publisher.py --show``).

Kinds of message (KINDS, with their shares):

* signed with the deployment's key, so they reach the decoders and the handlers:
  ``random`` bytes (half of them behind the type's fingerprint), ``truncated`` and
  ``bitflip`` copies of real messages, ``absurd``: a real message with one to three
  fields set to NaN, infinities, huge or negative numbers, booleans that are neither 0
  nor 1, empty, huge, control-character or non-UTF-8 strings, array counts that lie
  (2^31-1, negative, one more than sent) or thousands of elements; and ``valid`` real
  messages (plausible values: the demo's element ids, the arm's joints, skill labels);
* not authenticated: ``unsigned`` real messages (no trailer), ``bad_trailer`` (a trailer
  with random bytes, a wrong HMAC, a wrong length, the magic alone), ``wrong_key``,
  ``wrong_channel`` (signed for another channel), ``stale`` (signed 60 s ago) and
  ``replay`` (the last signed message again, byte for byte).

On an RPC channel most signed messages are a well-formed ``rpc_request_t`` naming one
of the server's methods with a fuzzed payload of that method's request type (so the
method's decoder and checks are what is fuzzed), the rest fuzz the envelope itself.

The messages are built by walking the generated Python classes (as codec_samples.py
does) with an encoder of our own that can write what LCM's cannot: counts and string
lengths that disagree with what follows, raw bytes for strings, booleans of any byte.
"""

from __future__ import annotations

import dataclasses
import math
import random
import struct
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parent))
from codec_samples import samples, type_class  # noqa: E402

# -- encoding -----------------------------------------------------------------------------

PACK = {"int8_t": struct.Struct(">b"), "int16_t": struct.Struct(">h"), "int32_t": struct.Struct(">i"),
        "int64_t": struct.Struct(">q"), "float": struct.Struct(">f"), "double": struct.Struct(">d"),
        "boolean": struct.Struct(">b"), "byte": struct.Struct(">B")}
INT_RANGE = {"int8_t": (-2 ** 7, 2 ** 7 - 1), "int16_t": (-2 ** 15, 2 ** 15 - 1),
             "int32_t": (-2 ** 31, 2 ** 31 - 1), "int64_t": (-2 ** 63, 2 ** 63 - 1), "byte": (0, 255),
             "boolean": (-128, 127)}
_U32 = struct.Struct(">I")


@dataclasses.dataclass
class Lying:
    """A string field written as `data` (bytes, any) behind a length prefix of `claimed`
    (LCM's prefix counts the terminating NUL), or an array whose elements are written as
    they are while its count field says something else (the count field is set apart)."""
    data: bytes
    claimed: int


def encode(msg: Any) -> bytes:
    """The LCM encoding of `msg` (fingerprint first), written field by field as the
    object holds them: a count field is written as set, whatever the array's length."""
    out: list[bytes] = [type(msg)._get_packed_fingerprint()]
    _encode_struct(msg, out)
    return b"".join(out)


def _encode_struct(m: Any, out: list[bytes]) -> None:
    cls = type(m)
    for slot, tn, dims in zip(cls.__slots__, cls.__typenames__, cls.__dimensions__):
        _encode_value(tn, list(dims or []), getattr(m, slot), out)


def _encode_value(tn: str, dims: list, v: Any, out: list[bytes]) -> None:
    if dims:
        if tn == "byte" and len(dims) == 1:
            out.append(bytes(v))
            return
        for x in v:
            _encode_value(tn, dims[1:], x, out)
        return
    p = PACK.get(tn)
    if p is not None:
        if tn in ("float", "double"):
            out.append(p.pack(float(v)))
        else:
            lo, hi = INT_RANGE[tn]
            out.append(p.pack(min(hi, max(lo, int(v)))))
    elif tn == "string":
        if isinstance(v, Lying):
            out.append(_U32.pack(v.claimed & 0xFFFFFFFF) + v.data)
        else:
            b = v if isinstance(v, (bytes, bytearray)) else str(v).encode("utf-8", "surrogatepass")
            out.append(_U32.pack(len(b) + 1) + bytes(b) + b"\0")
    else:
        _encode_struct(v, out)


def fields(cls: type):
    for slot, tn, dims in zip(cls.__slots__, cls.__typenames__, cls.__dimensions__):
        yield slot, tn, list(dims or [])


# -- plausible messages ---------------------------------------------------------------------

ELEMENTS = ["skiros:Cube-2", "skiros:Cube-3", "skiros:Cube-4", "skiros:Table-1", "skiros:Bin-5",
            "skiros:Robot-6", "skiros:Gripper-7", "skiros:Arm-8", "skiros:Scene-0", "skiros:Cube-99"]
CONCEPTS = ["skiros:Product", "skiros:Cube", "skiros:Location", "skiros:Table", "skiros:Bin", "skiros:Gripper",
            "skiros:Arm", "skiros:Robot", "skiros:Scene", "skiros:Thing"]
PREDICATES = ["skiros:contain", "skiros:hasA", "skiros:at", "skiros:partOf"]
PROPERTIES = ["skiros:PositionX", "skiros:PositionY", "skiros:PositionZ", "skiros:OrientationW", "skiros:Size",
              "skiros:FrameId", "skiros:Weight", "rdfs:label", "skiros:DiscreteReasoner"]
SKILLS = ["ClearTable", "Pick", "Place", "GripperOpen", "GripperClose", "Grasp", "Release", "Locate", "MoveArm",
          "LiftArm", "TransferProducts", "gripper_open", "gripper_close", "grasp", "release", "locate", "move_arm",
          "lift_arm", "pick", "place", "transfer_products", "clear_table"]
PARAM_KEYS = ["Gripper", "Object", "Location", "Arm", "Table", "Bin", "Command", "Robot", "Target", "N"]
PROCESSORS = ["Sequential", "SerialStar", "ParallelFf", "ParallelFs", "Selector", "RetryOnFail", "NoFail"]
JOINTS = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6"]
CHANNELS = ["SB_SIM_STATE", "SB_DEMO_CMD", "SB_DEMO_STATE", "SB_WM_TXN", "SB_WM_CHANGES", "SB_ROBOT_ARM_CMD",
            "SB_SIM_GRIPPER_CMD", "SB_SKILL_PROGRESS", "SB_CAN_SYNC"]
JSONS = ['{"a": 1}', "[1, 2, 3]", '"text"', "0.5", "null", "true", '{"x": [0.1, 0.2]}']
WORDS = ["a", "x", "open", "close", "grasp", "demo", "gripper0", "skills", "operator"]


@dataclasses.dataclass
class Context:
    """What the system under test calls things: plausible messages use these names (a
    clock from its master listing its participants, ticks for its skill process)."""
    participants: list[str] = dataclasses.field(default_factory=lambda: ["wm", "skill_mgr", "skills", "gripper"])
    master: str = "sim"
    processes: list[str] = dataclasses.field(default_factory=lambda: ["skills"])
    scenes: list[str] = dataclasses.field(default_factory=lambda: ["demo", "nope"])
    frame: int = -1  # the lockstep frame now (the publisher follows the master's clock), -1: unknown


# (type, field) first, then field: the pool a plausible string field draws from.
STRING_POOLS: dict[Any, Any] = {
    ("wm_property_t", "key"): PROPERTIES, ("skill_param_t", "key"): PARAM_KEYS,
    ("wm_element_t", "type"): CONCEPTS, ("wm_query_t", "type"): CONCEPTS, ("skill_start_t", "type"): SKILLS,
    ("skill_description_t", "type"): SKILLS, ("skill_tree_node_t", "type"): SKILLS,
    ("skill_tick_t", "label"): SKILLS, ("skill_start_t", "label"): SKILLS, ("skill_description_t", "label"): SKILLS,
    ("skill_tree_node_t", "label"): SKILLS, ("skill_condition_t", "label"): PARAM_KEYS,
    ("wm_element_t", "label"): ["red", "green", "blue", "table", "bin", ""],
    ("skill_tree_node_t", "processor"): PROCESSORS, ("wm_transform_t", "source"): ELEMENTS,
    ("wm_transform_t", "target"): ELEMENTS, ("wm_relation_t", "predicate"): PREDICATES,
    ("skill_condition_t", "owl"): PREDICATES + PROPERTIES, ("skill_param_t", "concept"): CONCEPTS,
    ("skill_param_t", "data_type"): ["element", "string", "int", "float", "bool", "list"],
    ("skill_condition_t", "kind"): ["ConditionRelation", "ConditionProperty", "ConditionHasProperty",
                                    "ConditionIsSpecified", "AbstractConditionRelation"],
    ("skill_condition_t", "op"): ["=", "!=", ">", "<", ""],
    ("sim_gripper_cmd_t", "id"): ["g1", "g2"], ("robot_arm_cmd_t", "id"): ["a1", "a2"],
    ("wm_scene_t", "path"): ["demo", "fuzz", "../x", "/etc/passwd", ""],
    ("wm_scene_t", "turtle"): ["", "@prefix skiros: <http://rvmi.aau.dk/ontologies/skiros.owl#> .\n",
                               "skiros:Cube-9 a skiros:Cube .", "<<<"],
    ("sim_control_t", "scene"): ["demo", "nope", "../demo", ""],
    "id": ELEMENTS, "ids": ELEMENTS, "subject": ELEMENTS, "object": ELEMENTS, "after": ELEMENTS + [""],
    "joint_names": JOINTS, "rpc_area": ["SKPROC_SKILLS", "SKPROC_FUZZ"], "channel": CHANNELS,
    "can_channel": ["gripper0"], "kind": ["python", "wm_server"], "s": JSONS + ELEMENTS + WORDS,
    "processor": PROCESSORS, "remap_from": PARAM_KEYS, "remap_to": PARAM_KEYS, "options": WORDS,
}


class Builder:
    """Plausible messages: small counts, sane numbers, the names of the system."""

    def __init__(self, rng: random.Random, ctx: Context) -> None:
        self.rng, self.ctx = rng, ctx

    def message(self, name: str) -> Any:
        m = self.struct(type_class(name))
        fix = FIXUPS.get(name)
        if fix is not None:
            fix(self, m)
        return m

    def struct(self, cls: type) -> Any:
        m = cls()
        tname = cls.__name__
        lengths = {d for _, _, dims in fields(cls) for d in dims if isinstance(d, str)}
        for slot, tn, dims in fields(cls):
            if slot in lengths:
                setattr(m, slot, self.rng.randint(0, 2) if tn != "int32_t" or slot != "num_joints" else 6)
                continue
            sizes = [getattr(m, d) if isinstance(d, str) else d for d in dims]
            setattr(m, slot, self.value(tname, slot, tn, sizes))
        return m

    def value(self, tname: str, slot: str, tn: str, sizes: list[int]) -> Any:
        rng = self.rng
        if sizes:
            if tn == "byte" and len(sizes) == 1:
                return bytes(rng.randrange(256) for _ in range(sizes[0]))
            if slot == "joint_names":
                return list(JOINTS[:sizes[0]]) + [f"joint{i + 7}" for i in range(max(0, sizes[0] - 6))]
            return [self.value(tname, slot, tn, sizes[1:]) for _ in range(sizes[0])]
        if tn == "string":
            pool = STRING_POOLS.get((tname, slot)) or STRING_POOLS.get(slot)
            if slot in ("sender", "participant"):
                pool = self.ctx.participants + [self.ctx.master]
            elif slot in ("process", "processes"):
                pool = self.ctx.processes
            elif slot == "participants":
                pool = self.ctx.participants
            return rng.choice(pool) if pool else rng.choice(WORDS)
        if tn in ("double", "float"):
            return rng.choice([0.0, 0.01, 0.1, 0.5, 1.0, -0.2])
        if tn == "boolean":
            return rng.random() < 0.3
        if tn == "byte":
            return rng.randrange(256)
        if tn in INT_RANGE:
            if slot in ("frame", "seq", "sim_time_ns", "count", "offset", "parent"):
                return rng.randint(0, 3)
            return rng.randint(0, 4) if tn == "int8_t" else rng.randint(0, 20)
        return self.struct(type_class(tn))


def _pose(rng: random.Random) -> list[float]:
    return [rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.8), rng.uniform(0.0, 0.8), 0.0, 0.0, 0.0, 1.0]


def _fix_header(b: Builder, m: Any) -> None:
    if hasattr(m, "header"):
        f = b.ctx.frame + b.rng.choice([0, 1, 1, 1, 2]) if b.ctx.frame >= 0 else b.rng.randint(0, 200)
        m.header.frame, m.header.sim_time_ns, m.header.seq = f, f * 20_000_000, 0


def _fix_clock(b: Builder, m: Any) -> None:
    _fix_header(b, m)
    m.header.sender = b.ctx.master
    m.participants = sorted(b.ctx.participants)
    m.num_participants = len(m.participants)
    m.frame_period_ns = 20_000_000
    m.stop, m.stop_reason = False, ""
    for c in m.counts:
        c.frame, c.count = m.header.frame - 1, 1


def _fix_arm_cmd(b: Builder, m: Any) -> None:
    _fix_header(b, m)
    m.joint_names, m.num_joints = list(JOINTS), 6
    for i, p in enumerate(m.points):
        p.time_from_start_ns = (i + 1) * 100_000_000
        p.positions, p.num_positions = [b.rng.uniform(-1, 1) for _ in range(6)], 6
        p.velocities, p.num_velocities = [], 0


def _fix_motion_request(b: Builder, m: Any) -> None:
    m.joint_names, m.num_joints = list(JOINTS), 6
    m.start = [b.rng.uniform(-1, 1) for _ in range(6)]
    m.target = _pose(b.rng)
    m.step_m, m.speed_scale = 0.01, 1.0


def _fix_arm_state(b: Builder, m: Any) -> None:
    _fix_header(b, m)
    m.joint_names, m.num_joints = list(JOINTS), 6
    m.position, m.velocity, m.effort = [0.1] * 6, [0.0] * 6, [0.0] * 6
    m.tool_pose = _pose(b.rng)


def _fix_sim_state(b: Builder, m: Any) -> None:
    _fix_header(b, m)
    m.tool_pose = _pose(b.rng)
    m.finger_width, m.finger_force, m.finger_width_target = b.rng.uniform(0, 0.08), 0.0, 0.08
    for o in m.objects:
        o.pose = _pose(b.rng)


def _fix_objects(b: Builder, m: Any) -> None:
    _fix_header(b, m)
    for o in m.objects:
        o.name, o.pose = b.rng.choice(["red", "green", "blue"]), _pose(b.rng)


def _fix_tick(b: Builder, m: Any) -> None:
    m.frame, m.sim_time_ns = -1, 0
    m.action = b.rng.randint(0, 4)


def _fix_value_types(b: Builder, m: Any) -> None:
    # every skill_value_t / wm_value_t inside: a known type with a value of that type
    def walk(x: Any) -> None:
        for slot, tn, dims in fields(type(x)):
            v = getattr(x, slot)
            if tn.endswith("skill_value_t") or tn.endswith("wm_value_t"):
                for e in (v if dims else [v]):
                    e.type = b.rng.randint(0, 5 if tn.endswith("skill_value_t") else 3)
                    if e.type == 5:
                        e.s = b.rng.choice(JSONS)
            elif "." in tn:
                for e in (v if dims else [v]):
                    walk(e)
    walk(m)


FIXUPS = {
    "lockstep_clock_t": _fix_clock, "robot_arm_cmd_t": _fix_arm_cmd, "motion_request_t": _fix_motion_request,
    "robot_arm_state_t": _fix_arm_state, "sim_state_t": _fix_sim_state, "robot_objects_t": _fix_objects,
    "skill_tick_t": lambda b, m: (_fix_tick(b, m), _fix_value_types(b, m)),
    "skill_start_t": _fix_value_types, "skill_register_t": _fix_value_types, "wm_txn_t": _fix_value_types,
    "wm_change_t": _fix_value_types, "wm_query_t": _fix_value_types,
}
def _fix_ack(b: Builder, m: Any) -> None:
    _fix_header(b, m)
    m.header.sender = b.rng.choice(b.ctx.participants)
    m.error = ""  # (an ack naming an error ends the session: that is what it is for)


FIXUPS["lockstep_ack_t"] = _fix_ack
for _name in ( "lockstep_end_t", "test_sample_t", "sim_gripper_cmd_t", "robot_cmd_reply_t",
              "skill_alive_t", "can_sync_t", "sim_cmd_reply_t", "skill_progress_t"):
    FIXUPS.setdefault(_name, _fix_header)


# -- absurd values --------------------------------------------------------------------------

ABSURD_DOUBLES = [math.nan, -math.nan, math.inf, -math.inf, 1e308, -1e308, 1e300, -1e9, -1.0, 5e-324, -0.0,
                  1e18, 2.0 ** 63, -2.0 ** 63, 1e-300]
ABSURD_FLOATS = [math.nan, math.inf, -math.inf, 3.4e38, -3.4e38, -1.0, 1e-45]


def absurd_int(rng: random.Random, tn: str) -> int:
    lo, hi = INT_RANGE[tn]
    return rng.choice([lo, hi, -1, lo + 1, hi - 1, 0, hi // 2 + 1, -hi // 3, 2 ** 31 - 1 if hi > 2 ** 31 else hi])


def absurd_string(rng: random.Random) -> Any:
    c = rng.randrange(12)
    if c == 0:
        return ""
    if c == 1:
        return "x" * rng.choice([1_000, 10_000, 60_000])
    if c == 2:
        return "é" * rng.choice([500, 5_000, 30_000])
    if c == 3:
        return "\x00\x01\x1b[31m\r\n\t\x7f"
    if c == 4:
        return bytes([0xff, 0xfe, 0xc3, 0x28, 0xed, 0xa0, 0x80])  # not UTF-8
    if c == 5:
        return rng.choice(["../../../etc/passwd", "/tmp/x", "..", "a/b", "%s%s%n", "${HOME}"])
    if c == 6:
        return rng.choice(["NaN", "Infinity", "-inf", "1e999", "[1e999]", '{"a": NaN}', "{", '"', "[[[[[[[["])
    if c == 7:
        return Lying(b"abc\0", rng.choice([2 ** 31 - 1, 2 ** 32 - 1, 0, 2 ** 31]))  # a length that lies
    if c == 8:
        return Lying(b"", rng.choice([5, 100, 65_536]))  # a length with nothing behind it
    if c == 9:
        return "skiros:" + "Cube-" * rng.choice([1, 50, 2_000]) + "2"
    if c == 10:
        return "\ud800" if rng.random() < 0.5 else "a\u202eb\ufeff"  # a lone surrogate (surrogatepass), bidi
    return "[" * 5_000 + "]" * 5_000


def leaves(m: Any, path: str = "") -> list[tuple[Any, str, str, list, str]]:
    """Every field of `m` and its substructures: (object, slot, typename, dims, path)."""
    out = []
    for slot, tn, dims in fields(type(m)):
        v = getattr(m, slot)
        out.append((m, slot, tn, dims, f"{path}{slot}"))
        if "." in tn or (tn not in PACK and tn != "string"):
            for i, x in enumerate(v if dims else [v]):
                if dims and isinstance(x, list):
                    continue
                out.extend(leaves(x, f"{path}{slot}{f'[{i}]' if dims else ''}."))
    return out


def make_absurd(rng: random.Random, m: Any, cands: list | None = None) -> tuple[str, list]:
    """Sets one to three fields of `m` (anywhere inside it) to absurd values. Returns what
    it did (for --show) and how to undo it (`undo(...)`: pooled messages are reused)."""
    done: list[str] = []
    undo: list[tuple] = []

    def put(obj: Any, slot: str, value: Any) -> None:
        undo.append((setattr, obj, slot, getattr(obj, slot)))
        setattr(obj, slot, value)

    def put_item(seq: list, i: int, value: Any) -> None:
        undo.append((list.__setitem__, seq, i, seq[i]))
        seq[i] = value

    cands = cands if cands is not None else leaves(m)
    for _ in range(rng.choice([1, 1, 2, 3])):
        obj, slot, tn, dims, path = rng.choice(cands)
        length_fields = {d for _, _, ds in fields(type(obj)) for d in ds if isinstance(d, str)}
        v = getattr(obj, slot)
        if slot in length_fields:  # a count that lies about what follows
            new = rng.choice([2 ** 31 - 1, -1, -2 ** 31, int(v) + 1, int(v) + 1000, 0, 1 << 20])
            put(obj, slot, new)
            done.append(f"{path}={new} (count)")
        elif dims:
            if not v or len(dims) > 1:
                continue  # (a matrix: its rows are left alone)
            what = rng.randrange(3)
            if what == 1 and isinstance(dims[0], str):  # hundreds or thousands of elements, the count agreeing
                n = rng.choice([500, 3_000]) if tn != "string" and "." not in tn else rng.choice([20, 200])
                new = (list(v) * (n // max(1, len(v)) + 1))[:n] if not isinstance(v, bytes) else bytes(n)
                put(obj, slot, new)
                put(obj, dims[0], n)
                done.append(f"{path}: {n} elements")
                continue
            if isinstance(v, (bytes, bytearray)) or "." in tn:
                continue
            i = rng.randrange(len(v))
            if tn == "string":
                put_item(v, i, absurd_string(rng))
            elif tn in ("double", "float"):
                put_item(v, i, rng.choice(ABSURD_DOUBLES if tn == "double" else ABSURD_FLOATS))
            elif tn in INT_RANGE:
                put_item(v, i, absurd_int(rng, tn))
            else:
                continue
            done.append(f"{path}[{i}]={shown(v[i])}")
        elif tn == "double":
            put(obj, slot, rng.choice(ABSURD_DOUBLES))
            done.append(f"{path}={getattr(obj, slot)!r}")
        elif tn == "float":
            put(obj, slot, rng.choice(ABSURD_FLOATS))
            done.append(f"{path}={getattr(obj, slot)!r}")
        elif tn == "boolean":
            put(obj, slot, rng.choice([2, -1, 127, -128]))
            done.append(f"{path}={getattr(obj, slot)} (boolean)")
        elif tn in INT_RANGE:
            put(obj, slot, absurd_int(rng, tn))
            done.append(f"{path}={getattr(obj, slot)}")
        elif tn == "string":
            put(obj, slot, absurd_string(rng))
            done.append(f"{path}={shown(getattr(obj, slot))}")
    return "; ".join(done) or "nothing", undo


def revert(undo: list) -> None:
    for fn, target, key, old in reversed(undo):
        fn(target, key, old)


def shown(v: Any) -> str:
    text = repr(v.data[:20]) + f" claiming {v.claimed}" if isinstance(v, Lying) else repr(v)
    return text if len(text) <= 60 else f"{text[:40]}... ({len(text)} chars)"


# -- channels and kinds ---------------------------------------------------------------------

@dataclasses.dataclass
class Channel:
    """A channel to fuzz: its message type, or (an RPC request channel) its methods and
    their request types, or (an RPC reply channel) its methods and their reply types."""
    name: str
    type: str = ""
    methods: dict[str, str] = dataclasses.field(default_factory=dict)
    reply: bool = False
    weight: float = 1.0


MAX_BYTES = 64_000  # LCM sends larger messages in fragments: those are 5 % of the huge ones
SIGNED = ("random", "truncated", "bitflip", "absurd", "valid")
KINDS = {"random": 0.12, "truncated": 0.13, "bitflip": 0.20, "absurd": 0.33, "valid": 0.05,
         "unsigned": 0.07, "bad_trailer": 0.04, "wrong_key": 0.02, "wrong_channel": 0.01, "stale": 0.015,
         "replay": 0.015}


@dataclasses.dataclass
class Fuzzed:
    index: int
    channel: str
    kind: str
    payload: bytes       # the LCM bytes, before any trailer
    note: str = ""       # what was done to it (for --show)
    method: str = ""     # an RPC request: the method named
    request: bool = False  # a well-formed rpc_request_t (a server answers it)


class Generator:
    """Message i of a seed, for the given channels: the same bytes on every run."""

    def __init__(self, seed: int, channels: list[Channel], ctx: Context | None = None,
                 kinds: dict[str, float] | None = None) -> None:
        self.seed, self.channels, self.ctx = seed, channels, ctx or Context()
        self.kinds = kinds or KINDS
        self._kind_names = list(self.kinds)
        self._kind_cum = _cumulative(list(self.kinds.values()))
        self._chan_cum = _cumulative([c.weight for c in channels])
        self._canonical = {name: m.encode() for name, m in samples().items()}
        self.client_id = f"fuzz-{seed}"
        self._pools: dict[tuple, list] = {}

    POOL = 48  # plausible messages built per type (and channel), reused with fresh mutations

    def pool(self, type_name: str, ch: Channel | None) -> list:
        """Plausible messages of a type, built once per seed: [(message, its bytes, its leaves)]."""
        key = (type_name, ch.name if ch is not None and ch.methods else "")
        p = self._pools.get(key)
        if p is None:
            rng = random.Random(f"{self.seed}/{key}")
            p = self._pools[key] = []
            for _ in range(self.POOL):
                m = self._build(rng, type_name, ch)
                p.append((m, encode(m), leaves(m)))
        return p

    def pick(self, rng: random.Random, cum: list[float], items: list) -> Any:
        x = rng.random() * cum[-1]
        for c, it in zip(cum, items):
            if x < c:
                return it
        return items[-1]

    def message(self, i: int) -> Fuzzed:
        rng = random.Random(self.seed * 1_000_003 + i)
        ch = self.pick(rng, self._chan_cum, self.channels)
        kind = self.pick(rng, self._kind_cum, self._kind_names)
        body_kind = kind if kind in SIGNED else "valid"
        if ch.methods and not ch.reply and rng.random() < 0.8:
            # a well-formed request naming a method: its payload is what is fuzzed
            method = rng.choice(list(ch.methods)) if rng.random() < 0.97 else rng.choice(["nope", "", "GET"])
            inner_type = ch.methods.get(method) or rng.choice(list(ch.methods.values()))
            payload, note = self.body(rng, inner_type, body_kind)
            req = type_class("rpc_request_t")()
            req.client_id, req.request_id, req.deadline_ns = self.client_id, i + 1, 0
            req.method, req.payload, req.payload_size = method, payload, len(payload)
            return Fuzzed(i, ch.name, kind, encode(req), f"{method}: {note}", method, True)
        type_name = ch.type or ("rpc_reply_t" if ch.reply else "rpc_request_t")
        payload, note = self.body(rng, type_name, body_kind, ch)
        return Fuzzed(i, ch.name, kind, payload, note)

    def body(self, rng: random.Random, type_name: str, kind: str, ch: Channel | None = None) -> tuple[bytes, str]:
        if kind == "random":
            n = rng.choice([0, 1, 7, 8, 9, 16, 40, 100, 300, 1400])
            data = rng.randbytes(n)
            if rng.random() < 0.5:  # behind the right fingerprint: the decoder itself is fuzzed
                data = type_class(type_name)._get_packed_fingerprint() + data
            return data, f"random {len(data)} bytes"
        real = self.real(rng, type_name, ch)
        if kind == "truncated":
            cut = rng.randrange(0, max(1, len(real)))
            return real[:cut], f"cut at {cut} of {len(real)}"
        if kind == "bitflip":
            m = bytearray(real)
            flips = []
            for _ in range(rng.choice([1, 1, 2, 3, 8])):
                pos = rng.randrange(8, len(m)) if len(m) > 8 else rng.randrange(len(m))
                m[pos] ^= 1 << rng.randrange(8)
                flips.append(pos)
            return bytes(m), f"bits flipped at {flips}"
        if kind == "absurd":
            msg, _, cands = rng.choice(self.pool(type_name, ch))
            undo = self._live(rng, msg)
            what, more = make_absurd(rng, msg, cands)
            undo += more
            try:
                data = encode(msg)
            finally:
                revert(undo)
            if len(data) > MAX_BYTES and rng.random() > 0.05:  # a few beyond a datagram (LCM fragments)
                data = data[:MAX_BYTES]
                what += f" (cut at {MAX_BYTES} bytes)"
            return data, f"absurd: {what}"
        return real, "valid"

    def _build(self, rng: random.Random, type_name: str, ch: Channel | None) -> Any:
        if type_name in ("rpc_request_t", "rpc_reply_t") and ch is not None and ch.methods:
            method = rng.choice(list(ch.methods))
            inner = encode(Builder(rng, self.ctx).message(ch.methods[method]))
            m = type_class(type_name)()
            m.client_id, m.request_id, m.method = self.client_id, rng.randint(1, 10 ** 6), method
            if type_name == "rpc_request_t":
                m.deadline_ns = 0
            else:
                m.status, m.error = rng.randint(0, 3), ""
            m.payload, m.payload_size = inner, len(inner)
            return m
        return Builder(rng, self.ctx).message(type_name)

    def real(self, rng: random.Random, type_name: str, ch: Channel | None) -> bytes:
        """A real message of the type: the canonical sample (every field at an edge
        value) a quarter of the time, else a plausible one."""
        if rng.random() < 0.25 and type_name in self._canonical:
            return self._canonical[type_name]
        msg, data, _ = rng.choice(self.pool(type_name, ch))
        undo = self._live(rng, msg)
        if undo:
            data = encode(msg)
            revert(undo)
        return data

    def _live(self, rng: random.Random, msg: Any) -> list:
        """Under a live lockstep session (ctx.frame known): the message's stamp (and a
        clock's counts) at the frames now due, so that it is taken for one of them."""
        if self.ctx.frame < 0 or not hasattr(msg, "header"):
            return []
        f = self.ctx.frame + rng.choice([-1, 0, 1, 2, 3])
        undo = [(setattr, msg.header, "frame", msg.header.frame), (setattr, msg.header, "sim_time_ns",
                                                                   msg.header.sim_time_ns)]
        msg.header.frame, msg.header.sim_time_ns = f, f * 20_000_000
        for c in getattr(msg, "counts", []):
            undo.append((setattr, c, "frame", c.frame))
            c.frame = f - 1
        return undo


def _cumulative(ws: list[float]) -> list[float]:
    out, s = [], 0.0
    for w in ws:
        s += w
        out.append(s)
    return out


# -- trailers that do not verify --------------------------------------------------------------

def bad_trailer(rng: random.Random, payload: bytes, sealed: bytes) -> tuple[bytes, str]:
    """`payload` with a trailer that must not verify; `sealed` is the same payload
    properly sealed (to damage)."""
    body_len = len(sealed) - len(payload) - 6
    c = rng.randrange(7)
    if c == 0:  # random bytes where the HMAC is
        b = bytearray(sealed)
        end = len(b) - 6
        b[end - 32:end] = rng.randbytes(32)
        return bytes(b), "random HMAC"
    if c == 1:  # one bit of the trailer's fields
        b = bytearray(sealed)
        b[len(payload) + rng.randrange(body_len)] ^= 1 << rng.randrange(8)
        return bytes(b), "a bit of the trailer flipped"
    if c == 2:  # the length says more than there is
        b = bytearray(sealed)
        struct.pack_into("<H", b, len(b) - 6, rng.choice([len(b), 0xFFFF, body_len + 1, 0, 1]))
        return bytes(b), "a wrong trailer length"
    if c == 3:
        return payload + b"SBA1", "the magic alone"
    if c == 4:
        return payload + rng.randbytes(rng.randrange(0, 80)) + struct.pack("<H", rng.randrange(0, 200)) + b"SBA1", \
            "random trailer"
    if c == 5:  # the payload changed under a good trailer
        b = bytearray(sealed)
        if payload:
            b[rng.randrange(len(payload))] ^= 1
        else:
            b = bytearray(b"\0") + b
        return bytes(b), "payload changed after signing"
    return sealed[:-rng.randrange(1, 12)], "trailer cut"
