"""WorldModelInterface: the world-model client a skill uses (SkiROS2's method names).

Reads come from a local replica kept current by the server's change stream
(SB_WM_CHANGES), so they do not go over the wire; a gap in versions makes the replica
resync from a snapshot. Writes are transactions:

* outside lockstep they are RPC calls (wm.commit), answered once durable; the call
  returns when the replica has the change too (read your writes);
* inside a lockstep participant (``participant=``) they are published on SB_WM_TXN
  and applied by the server in canonical order in the next frame; their effect reaches
  the replica two frames later (``commit_async``).
"""

from __future__ import annotations

import bisect
import contextlib
import gc
from typing import Any

from skillbus import startup_heap
from skillbus.bus import Bus, channel
from skillbus.msgs import (decode, header_t, wm_change_t, wm_commit_t, wm_element_t, wm_elements_t, wm_op_t,
                           wm_query_t, wm_scene_t, wm_transform_t, wm_txn_t, wm_value_t)
from skillbus.rpc import RpcClient, RpcError, RpcRemoteError
from skillbus.validate import BadValue, Rejects, integer
from skillbus.waiting import poll_until
from skillbus.world.convert import check_op_msg, element_from_msg, op, relation_msg
from skillbus.world.element import Element
from skillbus.world.ontology_view import OntologyView
from skillbus.world.skiros2_queries import SkiROS2Queries
from skillbus.world.sparql import SparqlQueries
from skillbus.world.wire import ElementsPage, decode_elements, next_page_after, query_all

# tick_element's decoded elements kept (a process runs a few primitives at once, each with
# a few element parameters; the tick decoder keeps 32 distinct parameter encodings)
_TICK_ELEMENTS_KEPT = 256

__all__ = ["WorldModelError", "WorldModelInterface", "query_all"]

Relation = tuple[str, str, str]


class WorldModelError(RuntimeError):
    """A request the world model refused; the message says why."""


class WorldModelInterface(SparqlQueries, SkiROS2Queries):
    def __init__(self, bus: Bus, name: str = "wmi", participant: Any = None, timeout: float = 5.0) -> None:
        self.bus, self.participant, self.timeout = bus, participant, timeout
        self.rpc = RpcClient(bus, "WM", name)
        self._elements: dict[str, Element] = {}
        self._relations: set[Relation] = set()
        self._by_node: dict[str, set[Relation]] = {}
        # node -> its relations sorted (a deterministic order: a set's depends on the
        # process's string hashing), made when first read and kept sorted as they change:
        # an element with 10,000 relations is not sorted again at every read
        self._rel_cache: dict[str, tuple[Relation, ...]] = {}
        # tick_element: id(message) -> (message, its element, the relations it was made with)
        self._tick_elements: dict[int, tuple[wm_element_t, Element, tuple[Relation, ...]]] = {}
        self._ontology_cache: OntologyView | None = None  # the server's hierarchy and templates (ontology_view)
        self.version = -1
        self._txn_ids = 0
        self.results: dict[int, wm_commit_t] = {}  # lockstep: request id -> result
        # Transactions are named (client id, request id) for exactly-once. Under lockstep the
        # name must not vary between runs (it is in the digest): the participant's name.
        self._txn_client_id = f"lockstep:{participant.name}" if participant is not None else self.rpc.client_id
        self._stale = False
        self._collecting: list[wm_change_t] | None = None
        # Changes and results not acted on (skillbus.validate), by kind.
        self.rejects = Rejects(f"wm-client {name}")
        if participant is not None:
            participant.subscribe(channel("SB_WM_CHANGES"), lambda m: self._on_change(m.data))
            participant.subscribe(channel("SB_WM_TXN_RESULT"), self._on_result)
        else:
            self._sub = bus.subscribe(channel("SB_WM_CHANGES"), lambda ch, data: self._on_change(data))
        self.resync()
        if participant is not None:
            # The transaction names (lockstep:<name>, counter) are the same every run; a
            # restarted participant goes on from where the server's answers end, so its
            # first writes are never mistaken for retries of its previous run's.
            q = wm_commit_t()
            q.client_id = self._txn_client_id
            q.request_digest = bytes(32)  # (LCM's Python encodes a fixed byte array as long as it is)
            self._txn_ids = self._call("last_request", q, wm_commit_t).request_id

    # -- replica ----------------------------------------------------------
    SNAPSHOT_PAGE = 200  # elements per snapshot reply: small messages survive UDP (the server refuses > 128 KB)

    def resync(self) -> None:
        """Replaces the replica with the server's world: pages of the snapshot by id (a
        page is stable while others write), then the changes from the first page's version
        on, replayed over them, so a busy world still gives a replica at once. Falls back
        to reading again only when a change of that span never arrives."""
        last_error = ""
        for _attempt in range(5):
            self._collecting = []  # changes that arrive while the pages are read
            try:
                with _collector_paused():
                    elements, relations, first, last = self._read_pages()
                changes = self._changes_up_to(first, last)
            finally:
                collected, self._collecting = self._collecting, None
            if changes is None:
                last_error = f"changes {first + 1}..{last} of the world did not all arrive"
                continue
            # The old replica, if it was set aside with the process's start-up heap, goes
            # back to the collector; the new one is set aside again below.
            released = startup_heap.release()
            self._elements = elements
            self._relations, self._by_node, self._rel_cache = set(), {}, {}
            self._ontology_cache = None  # a scene load or add_class may bring classes
            for r in relations:
                self._add_rel(r)
            self.version = first
            for ch in changes + sorted((c for c in collected if c.version > last), key=lambda c: c.version):
                if ch.version == self.version + 1:
                    self._apply_change(ch)
            self._stale = False
            if released:
                startup_heap.set_aside()
            return
        raise WorldModelError(f"could not read the world: {last_error}")

    def _read_pages(self) -> tuple[dict[str, Element], set[Relation], int, int]:
        elements: dict[str, Element] = {}
        relations: set[Relation] = set()
        first = last = None
        after = ""
        while True:
            q = wm_query_t()
            q.after, q.limit = after, self.SNAPSHOT_PAGE
            page = self._call_elements("snapshot", q)
            first = page.version if first is None else first
            last = page.version
            elements.update((e.id, e) for e in page.elements)
            relations.update(page.relations)
            if len(page.elements) < self.SNAPSHOT_PAGE:
                return elements, relations, first, last
            try:
                after = next_page_after(after, page.elements[-1].id, "wm.snapshot")
            except RuntimeError as e:
                raise WorldModelError(str(e)) from None

    def _changes_up_to(self, first: int, last: int, timeout: float = 2.0) -> list | None:
        """The changes first+1..last in order (they were made while the pages were read),
        waiting for those still in flight; None if one never comes."""
        def have() -> dict[int, wm_change_t]:
            return {c.version: c for c in self._collecting if first < c.version <= last}
        if last > first and self.participant is None:
            poll_until(lambda: len(have()) >= last - first, timeout, step=self.bus.handle)
        got = have()
        if len(got) < last - first or any(c.reset for c in got.values()):
            return None
        return [got[v] for v in range(first + 1, last + 1)]

    def _fresh(self) -> None:
        if self._stale:
            self.resync()

    def _add_rel(self, r: Relation) -> None:
        if r in self._relations:
            return
        self._relations.add(r)
        for n in {r[0], r[2]}:
            self._by_node.setdefault(n, set()).add(r)
            cached = self._rel_cache.get(n)
            if cached is not None:
                i = bisect.bisect_left(cached, r)
                self._rel_cache[n] = cached[:i] + (r,) + cached[i:]

    def _remove_rel(self, r: Relation) -> None:
        if r not in self._relations:
            return
        self._relations.discard(r)
        for n in {r[0], r[2]}:
            self._by_node.get(n, set()).discard(r)
            cached = self._rel_cache.get(n)
            if cached is not None:
                i = bisect.bisect_left(cached, r)
                self._rel_cache[n] = cached[:i] + cached[i + 1:]

    def _relations_of(self, eid: str) -> tuple[Relation, ...]:
        """The relations touching `eid`, sorted."""
        got = self._rel_cache.get(eid)
        if got is None:
            got = self._rel_cache[eid] = tuple(sorted(self._by_node.get(eid, ())))
        return got

    def _on_change(self, data: bytes) -> None:
        ch = decode(wm_change_t, data)
        if ch is not None:
            try:
                integer(ch.version, "version", 1)  # version 0 is the empty world, before any change
                for i, o in enumerate(ch.ops):
                    check_op_msg(o, f"ops[{i}]")
            except BadValue as e:
                # Not applied, not even in part. The world model has the truth: if this was
                # a change the replica still needs (the server's, after all), it now misses
                # a version, so it resyncs from a snapshot at the next read instead of going
                # on without it (as after a lost change).
                self.rejects.record(channel("SB_WM_CHANGES"), e)
                if self._collecting is None and isinstance(ch.version, int) and ch.version > self.version:
                    self._stale = True
                return
        if ch is not None and self._collecting is not None:  # a resync is reading pages
            self._collecting.append(ch)
            return
        if ch is None or ch.version <= self.version or self._stale:
            return
        if ch.reset or ch.version != self.version + 1:
            # A scene load, or we missed a change: resync before the next read. Not here:
            # this handler may run inside another call's wait.
            self._stale = True
            return
        self._apply_change(ch)

    def _apply_change(self, ch: wm_change_t) -> None:
        for o in ch.ops:
            rel = (o.relation.subject, o.relation.predicate, o.relation.object)
            if o.kind in (wm_op_t.ADD_ELEMENT, wm_op_t.UPDATE_ELEMENT):
                self._elements[o.element.id] = element_from_msg(o.element)
            elif o.kind == wm_op_t.REMOVE_ELEMENT:
                self._elements.pop(o.element.id, None)
            elif o.kind == wm_op_t.ADD_RELATION:
                self._add_rel(rel)
            elif o.kind == wm_op_t.REMOVE_RELATION:
                self._remove_rel(rel)
        self.version = ch.version

    def _on_result(self, m) -> None:
        r = decode(wm_commit_t, m.data)
        if r is not None and r.client_id == self._txn_client_id:
            try:  # a result for a request never made would only fill `results`
                integer(r.request_id, "request_id", 1, self._txn_ids)
            except BadValue as e:
                self.rejects.record(m.channel, e)
                return
            self.results[r.request_id] = r

    def sync(self, version: int | None = None, timeout: float | None = None) -> None:
        """Dispatches the bus until the replica is at `version` (default: the server's)."""
        if version is None:
            version = self._server_version()
        poll_until(lambda: self.version >= version or self._stale, self.timeout if timeout is None else timeout,
                   step=self.bus.handle)
        if self.version < version:
            self.resync()

    def _server_version(self) -> int:
        return self._call("get", _query(), wm_elements_t).version  # no ids: just the version

    # -- reads (replica) ----------------------------------------------------
    def _with_relations(self, e: Element) -> Element:
        """A reader's copy of replica element `e` with the relations touching it, loaded
        as it is (Element._reader_copy: its parts are copied as they are first read)."""
        return Element._reader_copy(e, self._relations_of(e.id))

    def with_relations(self, e: Element) -> Element:
        """`e` (e.g. a skill's element parameter, which carries properties only) with the
        relations the replica has for its id (beside its own), marked as loaded (see
        update_element): a copy, which shares nothing with `e`."""
        self._fresh()
        if not e.id or e.id not in self._elements:
            return e
        return self._complete(e.clone())

    def add_relations(self, e: Element) -> Element:
        """As with_relations, but into `e` itself, which is returned: for an element the
        caller has just made and nobody else holds (a tick's parameter, decoded afresh),
        which a copy would only duplicate. Marked as loaded either way (an element the
        replica does not have: with what it carries)."""
        self._fresh()
        return self._complete(e)

    def tick_element(self, m: wm_element_t) -> Element:
        """A tick parameter's element from its message: what element_from_msg(m) then
        add_relations give (its properties from `m`, the replica's relations of its id,
        marked as loaded), a new element every call that shares nothing that can change
        (what it was loaded as, loaded(), is read only, as every reader copy's).

        A task's parameters come back in the same bytes tick after tick, and the skill
        process's tick decoder then hands over the same message objects
        (skillbus.skill.tick_decode): the element is decoded once per message and relations
        of the replica (the same tuple while they have not changed), and each tick gets a
        reader's copy of it (Element._reader_copy: a property is copied when first read).
        The decoded element is kept here only, never handed out, so nothing changes it."""
        self._fresh()
        kept = self._tick_elements.get(id(m))
        if kept is not None and kept[0] is m and m.id in self._elements and self._relations_of(m.id) is kept[2]:
            return Element._reader_copy(kept[1], kept[2])
        e = element_from_msg(m)
        if not e.id or e.id not in self._elements:
            return self._complete(e)
        rels = self._relations_of(e.id)
        if any(s == "-1" or o == "-1" for s, _, o in rels):
            return self._complete(e)
        if len(self._tick_elements) >= _TICK_ELEMENTS_KEPT:
            self._tick_elements.clear()
        self._tick_elements[id(m)] = (m, e, rels)  # (m kept alive: its id names no other message)
        return Element._reader_copy(e, rels)

    def _complete(self, e: Element) -> Element:
        """`e` with the replica's relations of its id that it lacks, marked as loaded."""
        if e.id and e.id in self._elements:
            rels = self._relations_of(e.id)
            if not e._relations and not any(s == "-1" or o == "-1" for s, _, o in rels):
                # (a tick's parameter, made just now: its relations are the replica's, and
                # what it is loaded as is made from them, not read back from the dicts)
                e._relations = [{"src": s, "type": p, "dst": o, "state": True, "abstract": False} for (s, p, o) in rels]
                e.mark_loaded(resolved=frozenset(rels))
                return e
            have = {(r["src"], r["type"], r["dst"]) for r in e._relations if r.get("state", True)}
            e._relations += [{"src": s, "type": p, "dst": o, "state": True, "abstract": False}
                             for (s, p, o) in rels if (s, p, o) not in have]
        e.mark_loaded()
        return e

    def get_element(self, eid: str) -> Element:
        self._fresh()
        if eid not in self._elements:
            raise WorldModelError(f"no element {eid} in the world model (version {self.version})")
        return self._with_relations(self._elements[eid])

    def get_elements(self) -> list[Element]:
        self._fresh()
        return [self._with_relations(e) for _, e in sorted(self._elements.items())]

    def get_relations(self, subj: str = "", pred: str = "", obj: str = "") -> list[dict]:
        """The relations (as Element relation dicts, with the actual ids) that match: ""
        or "-1" is any element (SkiROS2 code passes "-1" for "any"), `pred` exactly."""
        subj, obj = _any(subj), _any(obj)
        self._fresh()
        pool = self._by_node.get(subj or obj, set()) if (subj or obj) else self._relations
        return [{"src": s, "type": p, "dst": o, "state": True, "abstract": False} for (s, p, o) in sorted(pool)
                if subj in ("", s) and pred in ("", p) and obj in ("", o)]

    def has_element(self, eid: str) -> bool:
        self._fresh()
        return eid in self._elements

    def has_relation(self, subj: str, pred: str, obj: str) -> bool:
        """Whether `subj` `pred` `obj` holds, a subproperty of `pred` counting (as in the
        skill manager's condition check); "" or "-1" is any element on that side (not on
        both). The replica answers, with the server's relation-type hierarchy."""
        subj, obj = _any(subj), _any(obj)
        if not subj and not obj:
            raise ValueError("has_relation needs a subject or an object")
        self._fresh()
        near = [r for r in self._by_node.get(subj or obj, ()) if subj in ("", r[0]) and obj in ("", r[2])]
        return any(not pred or self.is_subproperty(r[1], pred) for r in near)

    def is_instance_of(self, eid: str, concept: str) -> bool:
        """Whether element `eid`'s type is `concept` or a subclass of it (the replica, with
        the server's class hierarchy; an unknown concept has no instances)."""
        self._fresh()
        e = self._elements.get(eid)
        return e is not None and (e.type == concept or self.is_subclass(e.type, concept))

    def resolve_elements(self, e: Element) -> list[Element]:
        """The world's elements matching `e`, in id order, answered from the replica as the
        server's query answers (the same rules, tests/integration/test_wm_resolve.py): its
        type with its subclasses (the server's hierarchy; an unknown type raises
        WorldModelError), its label if set, every value of its properties that have values
        (of the same type), and its relations ("-1" or "" stands for the candidate, "*" for
        any element; a subproperty of the predicate counts)."""
        self._fresh()
        etype = e.type if e.type not in ("", "Unknown") else ""
        types: set[str] | None = None
        if etype:
            view = self.ontology_view()
            if not view.knows("classes", etype):
                raise WorldModelError(f"unknown type '{etype}' in query")
            types = set(view.below("classes", etype))
        label = e.label
        wanted = [(p.key, [(type(v), v) for v in p.values]) for p in e.properties if p.values]
        patterns = [(r["src"], r["type"], r["dst"]) for r in e.getRelations()]
        out = []
        with _collector_paused():
            for eid in sorted(self._elements):
                cand = self._elements[eid]
                if (types is not None and cand._type not in types) or (label and cand._label != label):
                    continue
                if wanted and not _has_values(cand, wanted):
                    continue
                if patterns and not all(self._holds(eid, pat) for pat in patterns):
                    continue
                out.append(self._with_relations(cand))
        return out

    def _holds(self, eid: str, pattern: tuple[str, str, str]) -> bool:
        """Whether a relation of the pattern touches `eid` ("-1" or "": `eid`; "*": any)."""
        s, p, o = pattern
        s = eid if s in ("-1", "") else s
        o = eid if o in ("-1", "") else o
        return any((s == "*" or r[0] == s) and (o == "*" or r[2] == o) and
                   (p in ("", "*") or self.is_subproperty(r[1], p)) for r in self._by_node.get(eid, ()))

    def query(self, q: wm_query_t) -> list[Element]:
        """The elements matching `q` (RPC wm.query), in id order, read in pages, so that a
        result of any size arrives (the server refuses a reply larger than 128 KB, naming
        paging). With ``q.ids_only`` they carry id, type and label only."""
        return query_all(lambda req, timeout: self._call_elements("query", req, timeout), q, timeout=self.timeout)

    # -- writes ----------------------------------------------------------------
    def commit(self, ops: list[wm_op_t], expected_version: int = -1) -> wm_commit_t:
        """Applies `ops` as one transaction and returns its result (version, new ids) once
        it is durable. Raises WorldModelError only when it was not applied (the server
        refused it, saying why). An applied write never raises: if the replica cannot
        catch up with it at once, the next read resyncs."""
        txn = self._txn(ops, expected_version)
        if self.participant is not None:
            raise WorldModelError("inside a lockstep participant, write with commit_async()")
        result = self._call("commit", txn, wm_commit_t)
        try:
            self.sync(result.version)  # read your writes
        except (WorldModelError, RpcError):
            self._stale = True  # applied and durable all the same: the next read catches up
        return result

    def commit_async(self, ops: list[wm_op_t], expected_version: int = -1) -> int:
        """Lockstep: publishes the transaction for this frame; returns its request id
        (its result appears in `results` when the server's answer arrives)."""
        if self.participant is None:
            raise WorldModelError("commit_async needs a lockstep participant")
        txn = self._txn(ops, expected_version)
        self.participant.publish(channel("SB_WM_TXN"), txn)
        return txn.request_id

    def _txn(self, ops: list[wm_op_t], expected_version: int) -> wm_txn_t:
        txn = wm_txn_t()
        txn.header = header_t()
        self._txn_ids += 1
        txn.client_id, txn.request_id = self._txn_client_id, self._txn_ids
        txn.expected_version = expected_version
        txn.ops, txn.num_ops = ops, len(ops)
        return txn

    def _relation_ops(self, e: Element, eid: str) -> list[wm_op_t]:
        want = set(e._resolved_relations() if eid == e.id else
                   [(eid if s == "-1" else s, p, eid if o == "-1" else o) for (s, p, o) in e._resolved_relations()])
        have = set(self._by_node.get(eid, ()))
        return ([op(wm_op_t.REMOVE_RELATION, relation=r) for r in sorted(have - want)] +
                [op(wm_op_t.ADD_RELATION, relation=r) for r in sorted(want - have)])

    def add_element(self, e: Element) -> Element:
        """Adds `e` with its relations; returns it with the id the server gave it."""
        result = self.commit([op(wm_op_t.ADD_ELEMENT, element=e)])
        eid = result.ids[0]
        rel_ops = self._relation_ops(e, eid)
        if rel_ops:
            self.commit(self._moving(rel_ops))
        e._id = eid
        return self.get_element(eid)

    def update_element(self, e: Element) -> Element:
        """Writes what changed in `e` since it was read (type, label, properties and the
        relations touching it); what `e` never carried stays as the world model has it.
        An element made by hand (never read) adds and overwrites what it carries and
        removes nothing."""
        if e.isAbstract():
            raise WorldModelError(f"cannot update {e.printState()}: it has no id (add it first)")
        self.commit(self._moving(self._update_ops(e, relations=True)))
        return self.get_element(e.id)

    def update_properties(self, e: Element) -> Element:
        """As update_element, for type, label and properties only."""
        self.commit(self._update_ops(e, relations=False))
        return self.get_element(e.id)

    def _update_ops(self, e: Element, relations: bool) -> list[wm_op_t]:
        self._fresh()
        current = self._elements.get(e.id)
        loaded = e.loaded()
        if current is None:
            merged = e  # not in the replica: the server says whether it exists
        else:
            merged = current.clone()
            base_type, base_label, base_props, _ = loaded or ("", "", {}, frozenset())
            if loaded is None or e.type != base_type:
                merged.type = e.type
            if loaded is None or e.label != base_label:
                merged.label = e.label
            for key, prop in e._properties.items():
                if loaded is None or base_props.get(key) != prop:
                    merged._properties[key] = prop
            if loaded is not None:
                for key in base_props:
                    if key not in e._properties:
                        merged._properties.pop(key, None)
        ops = [op(wm_op_t.UPDATE_ELEMENT, element=merged)]
        if relations:
            mine = set(e._resolved_relations())
            base = set(loaded[3]) if loaded is not None else set()
            have = set(self._by_node.get(e.id, ()))
            want = (have - (base - mine)) | (mine - base)
            ops += ([op(wm_op_t.REMOVE_RELATION, relation=r) for r in sorted(have - want)] +
                    [op(wm_op_t.ADD_RELATION, relation=r) for r in sorted(want - have)])
        return ops

    def remove_element(self, e: Element | str) -> None:
        eid = e if isinstance(e, str) else e.id
        self.commit([op(wm_op_t.REMOVE_ELEMENT, element=Element("", "", eid))])

    def set_relation(self, subj: str, pred: str, obj: str, value: bool = True) -> bool:
        """Adds (`value` True) or removes the relation; True (SkiROS2's "ok"). Nothing is
        written when the world model is already so; that is judged on the replica only
        once it has caught up with the server (a scene loaded meanwhile by another
        client, `skillbus wm load`, replaced the world the replica still shows)."""
        rel = (subj, pred, obj)

        def to_do() -> bool:
            self._fresh()
            return (rel in self._relations) != value

        if not to_do():
            self.sync()  # the replica may be behind the server: ask its version, catch up
            if not to_do():
                return True
        try:
            self.commit(self._moving([op(wm_op_t.ADD_RELATION if value else wm_op_t.REMOVE_RELATION, relation=rel)]))
        except WorldModelError:
            self.sync()  # (refused: the relation to remove is gone meanwhile?)
            if to_do():
                raise
        return True

    def _is_containment(self, pred: str) -> bool:
        return pred == "skiros:contain" or self.is_subproperty(pred, "skiros:contain")

    def _moving(self, ops: list[wm_op_t]) -> list[wm_op_t]:
        """`ops`, and for each element they put into a container (skiros:contain or below)
        the removal of its other containments the replica shows, in the same transaction.
        The world model keeps containment a tree (an element in two containers has no pose);
        SkiROS2 code moves an element in two writes (update_element of the new container,
        then of the element; set_relation, then the old relation's removal), so a write
        that adds a container moves the element, and the later write finds nothing to do."""
        added = [(m.relation.subject, m.relation.predicate, m.relation.object) for m in ops
                 if m.kind == wm_op_t.ADD_RELATION and self._is_containment(m.relation.predicate)]
        if not added:
            return ops
        removed = {(m.relation.subject, m.relation.predicate, m.relation.object) for m in ops
                   if m.kind == wm_op_t.REMOVE_RELATION}
        extra = []
        for rel in added:
            for r in sorted(self._by_node.get(rel[2], ())):
                if r[2] == rel[2] and r != rel and r not in removed and self._is_containment(r[1]):
                    extra.append(op(wm_op_t.REMOVE_RELATION, relation=r))
                    removed.add(r)
        return ops + extra

    def write_element_changes(self, e: Element) -> None:
        """Writes what changed in `e` since it was read (as update_element), if anything
        did: at once, or under lockstep with this frame (commit_async)."""
        if e.isAbstract():
            raise WorldModelError(f"cannot update {e.printState()}: it has no id (add it first)")
        if e.changed_since_loaded():
            self.write(self._update_ops(e, relations=True))

    def update_element_properties(self, e: Element, reasoner: str = "", context_id: str = "scene") -> Element:
        """SkiROS2's name of update_properties: type, label and properties, not relations."""
        if reasoner:
            raise NotImplementedError(f"update_element_properties(reasoner={reasoner!r}): skillbus has no reasoner "
                                      f"plug-ins (whose properties alone it would write)")
        return self.update_properties(e)

    def write(self, ops: list[wm_op_t]) -> None:
        """Commits `ops`: at once, or under lockstep with this frame (commit_async)."""
        if not ops:
            return
        if self.participant is not None:
            self.commit_async(ops)
        else:
            self.commit(ops)

    def set_parent(self, eid: str, parent: str, relation: str = "skiros:contain") -> None:
        """Makes `parent` the only element that contains `eid`, keeping its world pose
        (poses are relative to the container: the pose is re-expressed relative to the new
        one in the same transaction, see skillbus.world.poses.reparent). Under lockstep the
        write goes out with this frame (commit_async); otherwise it is committed at once."""
        from skillbus.world.poses import reparent_ops
        self.write(reparent_ops(self, eid, parent, relation=relation))

    # -- server-side questions -----------------------------------------------
    def get_transform(self, source: str, target: str) -> tuple[list[float], list[float]]:
        """Pose of `source` in `target`: (translation xyz, quaternion xyzw)."""
        req = wm_transform_t()
        req.source, req.target = source, target
        rep = self._call("transform", req, wm_transform_t)
        return list(rep.translation), list(rep.rotation)

    def may_relate(self, subject_type: str, relation: str, object_type: str) -> bool:
        """Abstract (concept-level) relation: may a `subject_type` `relation` an `object_type`?"""
        return self._call("may_relate", relation_msg(subject_type, relation, object_type), wm_value_t).b

    def load_scene(self, path: str | None = None, turtle: str | None = None, name: str | None = None) -> str:
        """Replaces the world with a Turtle scene: the file at `path` here (its text is sent),
        the `turtle` text, or, by `name`, the scene DATA/scenes/NAME.ttl on the server. A
        text over 16 MiB cannot be sent (the bus refuses it, naming the limit): a scene that
        large goes in the server's scenes folder and is loaded by name. Returns the
        server's report (what it skipped or noted)."""
        req = wm_scene_t()
        if name is not None:
            req.path = name  # (the server's field: a scene's name in its folder, never a path)
        elif path is not None:
            with open(path, encoding="utf-8") as f:  # read here: the server may be on another host
                req.turtle = f.read()
        else:
            req.turtle = turtle or ""
        rep = self._call("load_scene", req, wm_scene_t, timeout=max(self.timeout, 30.0))
        self.sync(rep.version)
        return rep.report

    def save_scene(self, path: str | None = None) -> str:
        rep = self._call("save_scene", wm_scene_t(), wm_scene_t, timeout=max(self.timeout, 30.0))
        if path is not None:
            with open(path, "w", encoding="utf-8") as f:
                f.write(rep.turtle)
        return rep.turtle

    def _call_elements(self, method: str, req: wm_query_t, timeout: float | None = None) -> ElementsPage:
        """A call whose reply is a wm_elements_t, decoded straight into Elements."""
        try:
            data = self.rpc.call_raw(method, req.encode(), timeout=timeout or self.timeout)
        except RpcRemoteError as e:
            raise WorldModelError(str(e)) from None
        try:
            return decode_elements(data)
        except ValueError as e:
            raise RpcError(f"reply of WM.{method} does not decode: {e}") from None

    def _call(self, method: str, req: Any, rep_type: type, timeout: float | None = None) -> Any:
        try:
            return self.rpc.call(method, req, rep_type, timeout=timeout or self.timeout)
        except RpcRemoteError as e:
            raise WorldModelError(str(e)) from None


@contextlib.contextmanager
def _collector_paused():
    """The cyclic garbage collector off while a burst of objects without cycles is made
    (the copies of thousands of elements): reference counting frees them, and the
    collections the burst would trigger walk every young object, several times."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def _has_values(e: Element, wanted: list[tuple[str, list[tuple[type, Any]]]]) -> bool:
    """Whether `e` has each property of `wanted` with each of its values (a value of
    another type is another value: 1 is not 1.0, as in the server)."""
    props = e._properties
    for key, values in wanted:
        p = props.get(key)
        if p is None:
            return False
        have = p._values
        if not all(any(type(h) is t and h == v for h in have) for t, v in values):
            return False
    return True


def _any(end: str) -> str:
    """A relation end as a filter: "-1" (SkiROS2's "this element", used in its client
    calls for "any") and "" are any."""
    return "" if end == "-1" else end


def _query(ids: list[str] | None = None, type_: str = "", label: str = "", exact: bool = False) -> wm_query_t:
    q = wm_query_t()
    q.ids = ids or []
    q.num_ids = len(q.ids)
    q.type, q.exact_type, q.label = type_, exact, label
    return q

