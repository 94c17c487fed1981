"""The console's world-model page: the containment tree, elements, search and edits.

An element is read from the server (``WM.get``) as it is stored; the console keeps that
read under a token and gives the token to the browser. An edit names the token: the
console sends the read element with an ``EXPECT_ELEMENT`` operation in the same
transaction as the change, and the server applies both or neither. So an edit of an
element that changed since it was read (a skill moved the cube, another console renamed
it) is refused, naming what changed, instead of overwriting what the user never saw.
"""

from __future__ import annotations

import collections
import hashlib
import math
from typing import Any

from skillbus.channels import channel
from skillbus.msgs import (decode, wm_change_t, wm_element_t, wm_elements_t, wm_op_t, wm_property_t, wm_query_t,
                           wm_relation_t, wm_value_t)
from skillbus.rpc import RpcClient, RpcError, RpcRemoteError, RpcTimeout
from skillbus.console.live import ConsoleError, ConsoleTimeout, text_field

VALUE_TYPES = {"string": wm_value_t.STRING, "int": wm_value_t.INT, "float": wm_value_t.FLOAT, "bool": wm_value_t.BOOL}
TYPE_NAMES = {v: k for k, v in VALUE_TYPES.items()}
READS_KEPT = 2000
WM_TIMEOUT_S = 3.0


def value_json(v: wm_value_t) -> Any:
    if v.type == wm_value_t.FLOAT and not math.isfinite(v.f):
        return str(v.f)  # (JSON has no NaN or infinity: "nan", "inf")
    return {wm_value_t.STRING: v.s, wm_value_t.INT: v.i, wm_value_t.FLOAT: v.f, wm_value_t.BOOL: v.b}.get(v.type)


def parse_value(text: Any, type_name: str) -> wm_value_t:
    """A value typed in the page, as the property's type; ConsoleError naming a bad one.

    >>> parse_value("0.25", "float").f, parse_value("true", "bool").b, parse_value(3, "int").i
    (0.25, True, 3)
    """
    v = wm_value_t()
    if type_name not in VALUE_TYPES:
        raise ConsoleError(f"unknown value type {type_name!r} (one of {', '.join(VALUE_TYPES)})")
    v.type = VALUE_TYPES[type_name]
    raw = str(text).strip() if not isinstance(text, (bool, int, float)) else text
    try:
        if type_name == "string":
            v.s = str(text)
        elif type_name == "int":
            if isinstance(raw, float) or isinstance(raw, bool):
                raise ValueError
            v.i = int(raw)
        elif type_name == "float":
            if isinstance(raw, bool):
                raise ValueError
            v.f = float(raw)
        else:
            lowered = str(raw).lower()
            if lowered not in ("true", "false", "1", "0"):
                raise ValueError
            v.b = lowered in ("true", "1")
    except ValueError:
        raise ConsoleError(f"{text!r} is not a {type_name}") from None
    return v


def element_json(e: wm_element_t) -> dict[str, Any]:
    return {"id": e.id, "type": e.type, "label": e.label,
            "properties": [{"key": p.key, "type": TYPE_NAMES.get(p.values[0].type, "?") if p.values else "string",
                            "values": [value_json(v) for v in p.values]} for p in e.properties]}


class LiveWorld:
    def __init__(self, bus, emit=None) -> None:
        self.bus, self.emit = bus, emit
        self.rpc = RpcClient(bus, "WM", "console")
        self._wmi = None
        self._reads: collections.OrderedDict[str, bytes] = collections.OrderedDict()
        self.version_heard = self._version_said = -1
        bus.subscribe(channel("SB_WM_CHANGES"), self._on_change)

    def _on_change(self, ch: str, data: bytes) -> None:
        c = decode(wm_change_t, data)
        if c is not None:
            self.version_heard = max(self.version_heard, c.version)

    def say_version(self) -> None:
        """Chore: tells browsers the world's version when it changed (at most each period,
        however fast the world changes)."""
        if self.emit is not None and self.version_heard != self._version_said:
            self._version_said = self.version_heard
            self.emit({"kind": "world", "version": self.version_heard})

    @property
    def wmi(self):
        """The world-model client with its replica, made at the first use (the server may
        start after the console)."""
        if self._wmi is None:
            from skillbus.world.client import WorldModelError, WorldModelInterface
            try:
                self._wmi = WorldModelInterface(self.bus, "console", timeout=WM_TIMEOUT_S)
            except (WorldModelError, RpcError) as e:
                raise ConsoleError(f"no world model: {e}") from None
        return self._wmi

    def _call(self, method: str, req, reply_type):
        try:
            return self.rpc.call(method, req, reply_type, timeout=WM_TIMEOUT_S)
        except RpcTimeout:
            raise ConsoleTimeout(f"the world model server did not answer WM.{method} within {WM_TIMEOUT_S:g} s") \
                from None
        except RpcRemoteError as e:
            raise ConsoleError(str(e)) from None

    def tree(self) -> dict[str, Any]:
        from skillbus.world.cli import containment_tree
        roots = containment_tree(self.wmi)  # (first: reading it may resync the replica to a later version)
        return {"version": self.wmi.version, "roots": roots}

    def search(self, type_: str, label: str) -> list[dict[str, Any]]:
        """Elements of a type (with its subclasses; "" any) whose label contains `label`
        (ignoring case; "" any)."""
        from skillbus.world.wire import query_all
        q = wm_query_t()
        q.type, q.ids_only = type_, True
        # In pages: a type of thousands of elements is more than the server sends in one
        # reply (it refused it, naming paging, and the start form's picker failed).
        found = query_all(lambda req, timeout: self._call("query", req, wm_elements_t), q, timeout=WM_TIMEOUT_S)
        want = label.lower()
        return [{"id": e.id, "type": e.type, "label": e.label} for e in found if want in e.label.lower()]

    def element(self, eid: str) -> dict[str, Any]:
        q = wm_query_t()
        q.ids, q.num_ids = [eid], 1
        reply = self._call("get", q, wm_elements_t)
        found = [e for e in reply.elements if e.id == eid]
        if not found:
            raise ConsoleError(f"no element {eid} in the world model (version {reply.version})")
        e = found[0]
        data = e.encode()
        token = hashlib.sha256(data).hexdigest()[:20]
        self._reads[token] = data
        self._reads.move_to_end(token)
        while len(self._reads) > READS_KEPT:
            self._reads.popitem(last=False)
        rels = [[r.subject, r.predicate, r.object] for r in reply.relations if eid in (r.subject, r.object)]
        return dict(element_json(e), relations=sorted(rels), version=reply.version, read=token)

    def _read(self, token: str) -> wm_element_t:
        data = self._reads.get(token or "")
        if data is None:
            raise ConsoleError("this edit names no element read by this console (reload the element)")
        return wm_element_t.decode(data)

    def edit(self, req: dict[str, Any]) -> dict[str, Any]:
        """One edit from the page: {"op": "set_property" | "set_label" | "relate" |
        "unrelate" | "remove" | "add", ...}; the commit's version, or ConsoleError saying
        why it was refused."""
        kind = req.get("op")
        ops: list[wm_op_t] = []
        if kind == "add":
            typ, label, parent = text_field(req, "type"), text_field(req, "label", ""), text_field(req, "parent", "")
            if not typ:
                raise ConsoleError("a new element needs a type")
            return self._add(typ, label, parent)
        read = self._read(str(req.get("read", "")))
        ops.append(_op(wm_op_t.EXPECT_ELEMENT, element=read))
        if kind == "set_property":
            key = text_field(req, "key", "")
            if not key:
                raise ConsoleError("set_property needs a key")
            old = next((p for p in read.properties if p.key == key), None)
            type_name = str(req.get("type") or (TYPE_NAMES.get(old.values[0].type) if old and old.values else "")
                            or "")
            if not type_name:
                raise ConsoleError(f"{read.id} has no property {key}: say its value type")
            values = req.get("values")
            if not isinstance(values, list):
                raise ConsoleError("set_property needs a list of values")
            new = _copy(read)
            props = [p for p in new.properties if p.key != key]
            if values:
                p = wm_property_t()
                p.key, p.values = key, [parse_value(v, type_name) for v in values]
                p.num_values = len(p.values)
                props.append(p)
            new.properties, new.num_properties = sorted(props, key=lambda p: p.key), len(props)
            ops.append(_op(wm_op_t.UPDATE_ELEMENT, element=new))
        elif kind == "set_label":
            new = _copy(read)
            new.label = text_field(req, "label")  # (missing or null: refused, not an erased label)
            ops.append(_op(wm_op_t.UPDATE_ELEMENT, element=new))
        elif kind in ("relate", "unrelate"):
            r = wm_relation_t()
            r.subject, r.predicate, r.object = (text_field(req, k, "") for k in ("subject", "predicate", "object"))
            if read.id not in (r.subject, r.object) or not r.predicate:
                raise ConsoleError(f"a relation of {read.id} needs a predicate and {read.id} at one end")
            ops.append(_op(wm_op_t.ADD_RELATION if kind == "relate" else wm_op_t.REMOVE_RELATION, relation=r))
        elif kind == "remove":
            ops.append(_op(wm_op_t.REMOVE_ELEMENT, element=read))
        else:
            raise ConsoleError(f"unknown edit {kind!r} (set_property, set_label, relate, unrelate, remove or add)")
        return self._commit(ops)

    def _add(self, typ: str, label: str, parent: str) -> dict[str, Any]:
        """A new element, in its parent (skiros:contain) in the same transaction: its id
        is the one the server would give it (TYPE-N, N the server's next number), taken
        again with the next number if another client took it meanwhile."""
        for _attempt in range(5):
            q = wm_query_t()
            q.ids, q.num_ids = ([parent], 1) if parent else ([], 0)
            q.limit = 1
            where = self._call("get", q, wm_elements_t)
            if parent and not any(e.id == parent for e in where.elements):
                raise ConsoleError(f"no element {parent} to put the new element in")
            e = wm_element_t()
            e.id, e.type, e.label = f"{typ}-{where.next_id}", typ, label
            ops = [_op(wm_op_t.ADD_ELEMENT, element=e)]
            if parent:
                r = wm_relation_t()
                r.subject, r.predicate, r.object = parent, "skiros:contain", e.id
                ops.append(_op(wm_op_t.ADD_RELATION, relation=r))
            try:
                return self._commit(ops)
            except ConsoleError as err:
                if "exists already" not in str(err):
                    raise
        raise ConsoleError("could not add the element: other clients kept taking its id")

    def _commit(self, ops: list[wm_op_t]) -> dict[str, Any]:
        from skillbus.world.client import WorldModelError
        try:
            result = self.wmi.commit(ops)
        except WorldModelError as e:
            raise ConsoleError(f"refused: {e}") from None
        except RpcTimeout as e:
            raise ConsoleTimeout(f"{e}: whether the edit was made is unknown (read the element before editing "
                                 f"again)") from None
        except RpcError as e:
            raise ConsoleError(str(e)) from None
        return {"version": result.version, "ids": list(result.ids)}


def _op(kind: int, element: wm_element_t | None = None, relation: wm_relation_t | None = None) -> wm_op_t:
    o = wm_op_t()
    o.kind = kind
    o.element = element if element is not None else wm_element_t()
    o.relation = relation if relation is not None else wm_relation_t()
    return o


def _copy(e: wm_element_t) -> wm_element_t:
    return wm_element_t.decode(e.encode())
