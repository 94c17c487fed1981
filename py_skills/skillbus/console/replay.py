"""A recorded run (an LCM log of a lockstep session) for the console's replay: every
frame's physics state, task trees and world model, read once and indexed by frame.

* Frames are those the clock master started (SB_LOCKSTEP_CLOCK), each with its sim time.
* Task trees: the last progress of each task stamped at or before the frame.
* The world model: the first complete snapshot a client read in the run (WM.snapshot
  replies are on the bus, so in the log), then every change (SB_WM_CHANGES) stamped at
  or before the frame.
* The session digest, recomputed from the log as the master chains it
  (docs/lockstep.md, "The digest"). It equals the run's own only when the log holds
  every message the clocks announced; where the logger lost some (a large camera cloud
  whose fragments did not all arrive), the replay says which and how many.
"""

from __future__ import annotations

import bisect
import collections
import hashlib
import os
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from skillbus.auth import strip
from skillbus.lockstep import peek_stamp
from skillbus.msgs import (decode, lockstep_clock_t, robot_arm_cmd_t, rpc_reply_t, sim_state_t, skill_progress_t,
                           wm_change_t, wm_elements_t, wm_op_t)
from skillbus.skill.cli import progress_json


class ReplayError(RuntimeError):
    pass


def _len(b: bytes) -> bytes:
    return struct.pack("<I", len(b)) + b


@dataclass
class World:
    """Elements (id -> {type, label, properties}) and relations, changed by wm_change_t."""
    elements: dict[str, dict[str, Any]] = field(default_factory=dict)
    relations: set[tuple[str, str, str]] = field(default_factory=set)

    def copy(self) -> "World":
        return World({k: dict(v) for k, v in self.elements.items()}, set(self.relations))

    def add_page(self, page: wm_elements_t) -> None:
        for e in page.elements:
            self.elements[e.id] = _element(e)
        self.relations |= {(r.subject, r.predicate, r.object) for r in page.relations}

    def apply(self, change: wm_change_t) -> None:
        for o in change.ops:
            if o.kind in (wm_op_t.ADD_ELEMENT, wm_op_t.UPDATE_ELEMENT):
                self.elements[o.element.id] = _element(o.element)
            elif o.kind == wm_op_t.REMOVE_ELEMENT:
                self.elements.pop(o.element.id, None)
            elif o.kind == wm_op_t.ADD_RELATION:
                self.relations.add((o.relation.subject, o.relation.predicate, o.relation.object))
            elif o.kind == wm_op_t.REMOVE_RELATION:
                self.relations.discard((o.relation.subject, o.relation.predicate, o.relation.object))

    def tree(self) -> list[dict[str, Any]]:
        """The containment tree as the live page shows it (world.cli.containment_tree's form)."""
        children: dict[str, list[str]] = collections.defaultdict(list)
        contained = set()
        for s, p, o in self.relations:
            if p == "skiros:contain" and s in self.elements and o in self.elements:
                children[s].append(o)
                contained.add(o)

        def node(eid: str, seen: frozenset) -> dict[str, Any]:
            e, cycle = self.elements[eid], eid in seen
            return {"id": eid, "type": e["type"], "label": e["label"], "cycle": cycle,
                    "children": [] if cycle else [node(c, seen | {eid}) for c in sorted(children[eid])]}

        return [node(r, frozenset()) for r in sorted(set(self.elements) - contained)]


def _element(e) -> dict[str, Any]:
    return {"type": e.type, "label": e.label}


class ReplayLog:
    def __init__(self, path: str | Path) -> None:
        import lcm
        self.path = Path(path)
        if not self.path.is_file():
            raise ReplayError(f"no log file {self.path}")
        try:
            log = lcm.EventLog(str(self.path), "r")
        except (OSError, IOError) as e:
            raise ReplayError(f"cannot read {self.path}: {e}") from None
        self.frames: list[int] = []
        self.sim_time_ns: dict[int, int] = {}
        self.sim: dict[str, dict[int, sim_state_t]] = collections.defaultdict(dict)   # robot -> frame -> state
        self.progress: dict[tuple[str, int], list[tuple[int, skill_progress_t]]] = collections.defaultdict(list)
        self.arm_cmds: dict[str, list[tuple[int, robot_arm_cmd_t]]] = collections.defaultdict(list)
        self.changes: list[tuple[int, wm_change_t]] = []
        self._snapshot_pages: dict[tuple[str, int], dict[int, bytes]] = {}
        self._announced: collections.Counter = collections.Counter()
        self._stamped: dict[int, dict[str, list[tuple[int, str, bytes]]]] = collections.defaultdict(
            lambda: collections.defaultdict(list))
        self._participants: dict[int, list[str]] = {}
        self.master = ""
        # A system apart on one bus ($SKILLBUS_NAMESPACE) has every channel behind its
        # namespace: the channels are recognised behind it (the console's own namespace).
        self._namespace = os.environ.get("SKILLBUS_NAMESPACE", "")
        stopped_at = None
        try:
            for ev in log:
                stopped_at = self._take(ev.channel, strip(ev.data), stopped_at)
        except (OSError, IOError, ValueError) as e:
            if not self.frames:
                raise ReplayError(f"{self.path} is not an LCM log: {e}") from None
        finally:
            log.close()
        if not self.frames:
            raise ReplayError(f"{self.path} holds no lockstep clock: not a recording of a lockstep run")
        self.world0, self.world0_version = self._first_world()
        self.changes.sort(key=lambda fc: fc[1].version)
        self.digest, self.missing = self._digest()
        del self._stamped

    # -- reading ------------------------------------------------------------------
    def _take(self, ch: str, data: bytes, stopped_at):
        local = ch[len(self._namespace):] if self._namespace and ch.startswith(self._namespace) else ch
        base = local.rsplit("/", 1)[-1]
        robot = local[: -len(base) - 1] if "/" in local else ""
        if base == "SB_LOCKSTEP_CLOCK":
            c = decode(lockstep_clock_t, data)
            if c is not None:
                self.master = c.header.sender
                for cc in c.counts:
                    k = (cc.sender, cc.channel, cc.frame)
                    self._announced[k] = max(self._announced[k], cc.count)
                # (frame -1: the master waiting for joins, no frame)
                if not c.stop and c.header.frame >= 0 and c.header.frame not in self.sim_time_ns:
                    self.frames.append(c.header.frame)
                    self.sim_time_ns[c.header.frame] = c.header.sim_time_ns
                    self._participants[c.header.frame] = sorted(c.participants)
            return stopped_at
        if base == "SB_WM_REP":
            r = decode(rpc_reply_t, data)
            if r is not None and r.method == "snapshot" and r.status == rpc_reply_t.OK:
                self._snapshot_pages.setdefault((r.client_id, r.request_id), {})[r.chunk] = \
                    bytes(r.payload) + struct.pack("<i", r.chunks)
            return stopped_at
        if base in ("SB_LOCKSTEP_ACK", "SB_LOCKSTEP_JOIN"):
            # The protocol's own acks and joins: an ack is stamped too, but no participant
            # publishes it in a frame, so no session digest counts it (a recorder of both
            # lanes, or of DDS, has them; an ack's seq 0 would hide the sender's own first
            # message of the frame).
            return stopped_at
        stamp = peek_stamp(data)
        if stamp is None:
            return stopped_at
        self._stamped[stamp.frame][stamp.sender].append((stamp.seq, ch, data))
        if base == "SB_SIM_STATE":
            s = decode(sim_state_t, data)
            if s is not None:
                self.sim[robot][stamp.frame] = s
        elif base == "SB_SKILL_PROGRESS":
            p = decode(skill_progress_t, data)
            if p is not None:
                self.progress[(robot, p.task)].append((stamp.frame, p))
        elif base == "SB_ROBOT_ARM_CMD":
            c = decode(robot_arm_cmd_t, data)
            if c is not None:
                self.arm_cmds[robot].append((stamp.frame, c))
        elif base == "SB_WM_CHANGES":
            c = decode(wm_change_t, data)
            if c is not None:
                self.changes.append((stamp.frame, c))
        return stopped_at

    def _first_world(self) -> tuple[World, int]:
        """The world of the first snapshot read whole in the run: its pages, in order (a
        reader pages by id; each reply's version is where its page was read)."""
        # A snapshot read = the replies to one client's consecutive requests; take the
        # earliest client whose pages end with a short page.
        by_client: dict[str, list[tuple[int, wm_elements_t]]] = collections.defaultdict(list)
        for (client, req), chunks in sorted(self._snapshot_pages.items(), key=lambda kv: kv[0][1]):
            n = struct.unpack("<i", next(iter(chunks.values()))[-4:])[0]
            if len(chunks) != n:
                continue  # (a chunk lost in the log)
            payload = b"".join(chunks[i][:-4] for i in range(n))
            page = decode(wm_elements_t, payload)
            if page is not None:
                by_client[client].append((req, page))
        for client, pages in by_client.items():
            world = World()
            for _req, page in pages:
                world.add_page(page)
                if len(page.elements) < 200 or page.total == len(world.elements):
                    return world, pages[0][1].version
        return World(), 0

    def _digest(self) -> tuple[str, dict[str, int]]:
        """The session digest over the log's stamped messages, and how many announced
        messages the log lacks, by channel."""
        missing: collections.Counter = collections.Counter()
        have = collections.Counter((sender, ch, frame) for frame, by in self._stamped.items()
                                   for sender, msgs in by.items() for _seq, ch, _d in msgs)
        for k, n in self._announced.items():
            if have[k] < n:
                missing[k[1]] += n - have[k]
        d = bytes(32)
        for frame in self.frames:
            by = self._stamped.get(frame, {})

            def own(sender: str) -> bytes:
                h, seen = hashlib.sha256(), set()
                for seq, ch, data in sorted(by.get(sender, []), key=lambda m: m[0]):
                    if seq in seen:
                        continue  # (a datagram the logger heard twice)
                    seen.add(seq)
                    h.update(_len(ch.encode()))
                    h.update(_len(data))
                return h.digest()

            h = hashlib.sha256()
            h.update(d)
            h.update(struct.pack("<q", frame))
            h.update(own(self.master))
            for p in self._participants[frame]:
                h.update(_len(p.encode()))
                h.update(own(p))
            d = h.digest()
        return d.hex(), dict(missing)

    # -- at a frame -------------------------------------------------------------------
    def summary(self) -> dict[str, Any]:
        return {"file": str(self.path), "frames": len(self.frames), "first": self.frames[0], "last": self.frames[-1],
                "sim_time_s": self.sim_time_ns[self.frames[-1]] * 1e-9, "digest": self.digest,
                "missing": self.missing, "robots": sorted(self.sim), "tasks": len(self.progress),
                "world_from_version": self.world0_version,
                "scene_note": getattr(self, "scene_note", "")}  # (set where the run's own scene cannot be drawn)

    def nearest_frame(self, frame: int) -> int:
        i = bisect.bisect_right(self.frames, frame) - 1
        return self.frames[max(i, 0)]

    def tasks_at(self, frame: int) -> list[dict[str, Any]]:
        out = []
        for (robot, task), seq in sorted(self.progress.items()):
            i = bisect.bisect_right([f for f, _ in seq], frame) - 1
            if i < 0:
                continue
            p = progress_json(seq[i][1])
            out.append({"robot": robot, "task": task, "skill": p["nodes"][0]["type"] if p["nodes"] else "",
                        "state": p["state"], "tick": p["tick"], "nodes": p["nodes"]})
        return out

    def world_at(self, frame: int) -> World:
        w = self.world0.copy()
        for f, c in self.changes:
            if f <= frame and c.version > self.world0_version:
                w.apply(c)
        return w

    def sim_at(self, frame: int, robot: str | None = None) -> sim_state_t | None:
        states = self.sim.get(robot if robot is not None else (sorted(self.sim)[0] if self.sim else ""), {})
        if not states:
            return None
        keys = sorted(states)
        i = bisect.bisect_right(keys, frame) - 1
        return states[keys[max(i, 0)]]

    def arm_cmd_at(self, frame: int, robot: str = "") -> robot_arm_cmd_t | None:
        cmds = [c for f, c in self.arm_cmds.get(robot, []) if f <= frame]
        return cmds[-1] if cmds else None
