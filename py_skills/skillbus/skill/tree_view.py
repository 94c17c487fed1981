"""`skillbus tree TASK_OR_SKILL [--dot]`: a tree for people without a browser.

* A task id: the task's tree as its manager has it now (SKILL.tasks), with each node's
  state and message.
* A skill: the tree it expands to, before anything runs: the compound asks its skill
  process for its expansion (RPC ``expand``, as the manager does when it starts the
  skill), and so does each compound inside, with the values the tree gives it (specify)
  and what it inherits from its parent (remap, and keys of the same name), else its
  description's defaults. A compound whose expansion depends on the world (a planner)
  shows what it would do with the world as it is now.

ASCII by default; ``--dot`` prints Graphviz (``skillbus tree ClearTable --dot | dot -Tsvg``).
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field

from skillbus.msgs import skill_param_t, skill_start_t, skill_tick_t, skill_tree_t, skill_value_t
from skillbus.rpc import RpcClient, RpcError, RpcRemoteError
from skillbus.channels import expand_area

MAX_DEPTH = 12
EXPAND_TIMEOUT_S = 30.0


@dataclass
class TreeNode:
    name: str                      # the skill type, or "(Processor)" for an anonymous group
    processor: str = ""
    state: str = ""
    message: str = ""
    note: str = ""
    children: list["TreeNode"] = field(default_factory=list)


def ascii_lines(node: TreeNode, depth: int = 0) -> list[str]:
    """
    >>> print("\\n".join(ascii_lines(TreeNode("A", "SerialStar", children=[TreeNode("B", state="Success")]))))
    A [SerialStar]
      B Success
    """
    head = node.name + (f" [{node.processor}]" if node.processor and not node.name.startswith("(") else "")
    tail = " ".join(x for x in (node.state, f": {node.message}" if node.message else "",
                                f"({node.note})" if node.note else "") if x).replace(" :", ":")
    out = ["  " * depth + head + (f" {tail}" if tail else "")]
    for c in node.children:
        out += ascii_lines(c, depth + 1)
    return out


def dot_text(root: TreeNode, title: str) -> str:
    """Graphviz: a box per skill, an ellipse per anonymous group, edges parent -> child."""
    lines = [f"digraph {json.dumps(title)} {{", "  node [fontname=Helvetica, fontsize=11];", "  rankdir=TB;"]
    counter = [0]

    def walk(n: TreeNode) -> str:
        me = f"n{counter[0]}"
        counter[0] += 1
        label = n.name + (f"\\n[{n.processor}]" if n.processor and not n.name.startswith("(") else "")
        if n.state:
            label += f"\\n{n.state}" + (f": {n.message}" if n.message else "")
        shape = "ellipse" if n.name.startswith("(") else "box"
        color = {"Success": "palegreen", "Failure": "lightpink", "Running": "lightyellow"}.get(n.state, "white")
        lines.append(f"  {me} [label={json.dumps(label)}, shape={shape}, style=filled, fillcolor={color}];")
        for c in n.children:
            lines.append(f"  {me} -> {walk(c)};")
        return me

    walk(root)
    lines.append("}")
    return "\n".join(lines)


def from_progress(nodes) -> TreeNode:
    """A task's tree from its progress (skill_node_progress_t, preorder)."""
    from skillbus.skill.cli import STATES
    made: list[TreeNode] = []
    for n in nodes:
        t = TreeNode(n.type or f"({n.processor})", n.processor, STATES.get(n.state, "?"), n.message)
        made.append(t)
        if n.parent >= 0:
            made[n.parent].children.append(t)
    return made[0] if made else TreeNode("(empty)")


class Expander:
    """Expands a skill as the manager would, without running anything."""

    def __init__(self, bus, lst, robot: str | None) -> None:
        self.bus, self.robot = bus, robot
        self.impls = {}  # label -> (description, process); by type: the first label
        for d, proc in zip(lst.skills, lst.processes):
            self.impls[d.label] = (d, proc)
            self.impls.setdefault(("type", d.type), (d, proc))
        self.clients: dict[str, RpcClient] = {}
        self.wm = RpcClient(bus, "WM", "tree")
        self.grounded: dict[str, str] = {}  # key -> the element id filled in (said under the tree)

    def ground(self, p: skill_param_t) -> skill_param_t:
        """An element parameter without an element: the one element of its type, when the
        world model has exactly one (the manager grounds by the skill's pre-conditions;
        with several candidates, -p chooses)."""
        from skillbus.msgs import wm_elements_t, wm_query_t
        if p.data_type != "element" or (p.values and p.values[0].element.id) or not p.concept:
            return p
        q = wm_query_t()
        q.type = p.concept
        try:
            found = self.wm.call("query", q, wm_elements_t, timeout=3.0).elements
        except RpcError:
            return p
        if len(found) != 1:
            return p
        out = skill_param_t.decode(p.encode())
        v = skill_value_t()
        v.type, v.element = skill_value_t.ELEMENT, found[0]
        out.values, out.num_values = [v], 1
        self.grounded[p.key] = found[0].id
        return out

    def find(self, type_: str, label: str = ""):
        return self.impls.get(label) or self.impls.get(("type", type_))

    def expand(self, type_: str, label: str, given: dict[str, skill_param_t], depth: int = 0) -> TreeNode:
        found = self.find(type_, label)
        if found is None:
            return TreeNode(type_, note="no such skill registered")
        d, proc = found
        if not d.compound:
            return TreeNode(d.type)
        if depth >= MAX_DEPTH:
            return TreeNode(d.type, note=f"not expanded: {MAX_DEPTH} levels deep")
        params = {p.key: self.ground(given.get(p.key, p)) for p in d.params}
        t = skill_tick_t()
        t.label, t.action, t.frame, t.sim_time_ns = d.label, skill_tick_t.EXPAND, -1, 0
        t.params = [_named(p, k) for k, p in params.items() if p.values or k in given]
        t.num_params = len(t.params)
        area = expand_area(proc)  # (not the process's own area: that is the manager's alone)
        client = self.clients.setdefault(area, RpcClient(self.bus, area, "tree", robot=self.robot))
        try:
            tree = client.call("expand", t, skill_tree_t, timeout=EXPAND_TIMEOUT_S)
        except RpcError as e:
            return TreeNode(d.type, note=f"cannot expand: {e}")
        if tree.error:
            return TreeNode(d.type, note=f"cannot expand: {tree.error}")
        made: list[TreeNode] = []
        for i, n in enumerate(tree.nodes):
            if i == 0:
                node = TreeNode(d.type, n.processor)
            elif n.type:
                child_given = dict(params)  # what a child inherits: keys of the same name ...
                for frm, to in zip(n.remap_from, n.remap_to):  # ... remapped ones ...
                    if to in params:
                        child_given[frm] = params[to]
                for sp in n.specify:  # ... and values the tree gives it
                    child_given[sp.key] = sp
                node = self.expand(n.type, n.label, child_given, depth + 1)
            else:
                node = TreeNode(f"({n.processor})", n.processor)
            made.append(node)
            if i > 0:
                made[n.parent].children.append(node)
        return made[0]


def _named(p: skill_param_t, key: str) -> skill_param_t:
    if p.key == key:
        return p
    out = skill_param_t.decode(p.encode())
    out.key = key
    return out


def typed_param(d, text: str) -> skill_param_t:
    """-p KEY=VALUE typed by the skill's description (as the manager types it)."""
    if "=" not in text:
        raise ValueError(f"-p {text!r}: expected KEY=VALUE")
    key, raw = text.split("=", 1)
    decl = next((p for p in d.params if p.key == key), None)
    if decl is None:
        raise ValueError(f"{d.type} has no parameter {key} (it has: {', '.join(p.key for p in d.params) or 'none'})")
    v = skill_value_t()
    kind = decl.data_type
    try:
        if kind == "int":
            v.type, v.i = skill_value_t.INT, int(raw)
        elif kind == "float":
            v.type, v.f = skill_value_t.FLOAT, float(raw)
        elif kind == "bool":
            v.type, v.b = skill_value_t.BOOL, raw.lower() in ("1", "true", "yes")
        elif kind in ("list", "dict"):
            json.loads(raw)
            v.type, v.s = skill_value_t.JSON, raw
        elif kind == "element":
            v.type = skill_value_t.ELEMENT
            v.element.id, v.element.type = raw, decl.concept
        else:
            v.type, v.s = skill_value_t.STRING, raw
    except ValueError:
        raise ValueError(f"-p {text}: {key} takes a {kind}") from None
    p = skill_param_t.decode(decl.encode())
    p.values, p.num_values = [v], 1
    return p


def main(args) -> int:
    from skillbus.bus import open_bus
    from skillbus.skill.cli import NoManager, _task_req, call
    from skillbus.msgs import skill_list_t, skill_progress_list_t
    if args.target.isdigit() and args.param:  # (they were ignored without a word)
        print("error: tree: -p is for a skill's expansion; a task's tree is as it runs", file=sys.stderr)
        return 2
    bus = open_bus(args.url)
    client = RpcClient(bus, "SKILL", "tree")
    try:
        if args.target.isdigit():
            # (a manager that does not answer is said so, below: it was told as "does not know task N")
            try:
                known = call(client, "tasks", _task_req(int(args.target)), skill_progress_list_t)
                p = next((t for t in known.tasks if t.task == int(args.target)), None)
            except RpcRemoteError:  # (it answered: it does not know the task)
                p = None
            if p is None:
                print(f"error: the skill manager does not know task {args.target}", file=sys.stderr)
                return 2
            root, title = from_progress(p.nodes), f"task {args.target}"
        else:
            lst = call(client, "list", skill_start_t(), skill_list_t)
            ex = Expander(bus, lst, getattr(args, "robot", None))
            found = ex.find(args.target, args.target)
            if found is None:
                from skillbus.skill.cli import unknown_skill
                print(f"error: {unknown_skill(args.target, lst)}", file=sys.stderr)
                return 2
            try:
                given = {p.key: p for p in (typed_param(found[0], t) for t in args.param)}
            except ValueError as e:
                print(f"error: {e}", file=sys.stderr)
                return 2
            root, title = ex.expand(found[0].type, found[0].label, given), found[0].type
            if ex.grounded and not args.dot:
                print("(element parameters filled in with the only element of their type: " +
                      ", ".join(f"{k}={v}" for k, v in sorted(ex.grounded.items())) + ")", file=sys.stderr)
    except NoManager as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    print(dot_text(root, title) if args.dot else "\n".join(ascii_lines(root)))
    return 0


def add_parser(sub) -> None:
    t = sub.add_parser("tree", help="a skill's expanded tree before it runs, or a task's tree now (ASCII, or --dot)")
    t.add_argument("target", metavar="TASK_OR_SKILL", help="a task id, or a skill type (or implementation label)")
    t.add_argument("-p", "--param", action="append", default=[], metavar="KEY=VALUE",
                   help="a parameter's value for the expansion (default: the description's)")
    t.add_argument("--dot", action="store_true", help="Graphviz instead of ASCII")
    t.add_argument("--url", default=None)
    t.add_argument("--robot", default=None, metavar="NAME", help="the robot whose skill manager to ask")
