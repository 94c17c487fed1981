"""`skillbus wm ...`: look at and change the world model from a terminal."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

from skillbus.bus import open_bus
from skillbus.world.client import WorldModelError, WorldModelInterface
from skillbus.world.element import Element
from skillbus import cli_values


def add_parser(sub) -> None:
    wm = sub.add_parser("wm", help="the world model: get, query, load, save, tree, repair")
    wm.add_argument("--url", default=None, help="bus URL (default: $SKILLBUS_BUS_URL or the udpm default)")
    wm.add_argument("--timeout", type=cli_values.seconds, default=5.0)
    wsub = wm.add_subparsers(dest="wm_command", required=True)
    g = wsub.add_parser("get", help="show one element")
    g.add_argument("id")
    g.add_argument("--json", action="store_true")
    q = wsub.add_parser("query", help="elements of a type (with subclasses), optionally with a label")
    q.add_argument("--type", default="")
    q.add_argument("--label", default="")
    q.add_argument("--json", action="store_true")
    ld = wsub.add_parser("load", help="replace the world with a Turtle scene")
    ld.add_argument("file", help="a Turtle file here (its text is sent: at most 16 MiB), or with --on-server the "
                                 "name of a scene in the server's DATA/scenes")
    ld.add_argument("--on-server", action="store_true",
                    help="FILE names DATA/scenes/FILE.ttl on the server (any size; a name, never a path)")
    sv = wsub.add_parser("save", help="write the world as a Turtle scene")
    sv.add_argument("file")
    t = wsub.add_parser("tree", help="the containment tree with poses")
    t.add_argument("--json", action="store_true",
                   help="print the roots as a JSON list, each element with its position and children")
    r = wsub.add_parser("repair", help="check a server's data directory (no server may be using it); a damaged "
                                       "journal is replaced by its intact records before the damage, the original "
                                       "kept as journal.bin.corrupt")
    r.add_argument("--data", required=True, metavar="DIR", help="the data directory (wm_server --data)")


def element_dict(e: Element) -> dict:
    return {"id": e.id, "type": e.type, "label": e.label,
            "properties": {p.key: p.values for p in e.properties},
            "relations": [[r["src"], r["type"], r["dst"]] for r in e.getRelations()]}


def print_element(e: Element) -> None:
    print(f"{e.id}  ({e.type})  label={e.label!r}")
    for p in sorted(e.properties, key=lambda p: p.key):
        print(f"    {p.key} = {p.values[0] if len(p.values) == 1 else p.values}")
    for r in e.getRelations():
        print(f"    {r['src']} {r['type']} {r['dst']}")


def position(e: Element) -> list[float] | None:
    keys = ["skiros:PositionX", "skiros:PositionY", "skiros:PositionZ"]
    if not any(e.hasProperty(k) for k in keys):
        return None
    return [e.getProperty(k).value if e.hasProperty(k) else 0.0 for k in keys]


def containment_tree(wmi: WorldModelInterface) -> list[dict]:
    """The containment tree (skiros:contain) from its roots: each element's id, type,
    label, position (relative to its container; None without one) and children, sorted
    by id. Where the containment has a cycle, the element met again is shown once more
    with "cycle": true and no children."""
    elements = {e.id: e for e in wmi.get_elements()}
    children: dict[str, list[str]] = {}
    contained = set()
    for r in wmi.get_relations(pred="skiros:contain"):
        children.setdefault(r["src"], []).append(r["dst"])
        contained.add(r["dst"])

    def node(eid: str, seen: frozenset) -> dict:
        e, cycle = elements[eid], eid in seen
        return {"id": eid, "type": e.type, "label": e.label, "position": position(e), "cycle": cycle,
                "children": [] if cycle else [node(c, seen | {eid}) for c in sorted(children.get(eid, []))]}

    return [node(root, frozenset()) for root in sorted(set(elements) - contained)]


def print_tree(wmi: WorldModelInterface) -> None:
    def show(n: dict, depth: int) -> None:
        p = n["position"]
        at = " at ({:.3f}, {:.3f}, {:.3f})".format(*p) if p is not None else ""
        print("  " * depth + f"{n['id']} [{n['label']}]{at}")
        if n["cycle"]:
            print("  " * (depth + 1) + "(cycle)")
        for c in n["children"]:
            show(c, depth + 1)

    for root in containment_tree(wmi):
        show(root, 0)


def repair(data: str) -> int:
    """`skillbus wm repair --data DIR`: runs `wm_server --repair --data DIR` (the journal's
    one reader is the server's) and prints what it found and did: 0 when repaired or
    nothing was wrong, 1 when it cannot repair (the message says what a person can do)."""
    from skillbus import paths
    try:
        r = subprocess.run([str(paths.binary("wm_server")), "--repair", "--data", data], capture_output=True, text=True)
    except OSError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    for line in r.stdout.splitlines():
        print(line.removeprefix("wm_server: "))
    for line in r.stderr.splitlines():
        print(f"error: {line.removeprefix('wm_server: ')}", file=sys.stderr)
    return r.returncode


def main(args: argparse.Namespace) -> int:
    if args.wm_command == "repair":  # the files only: no server may be running on them
        return repair(args.data)
    try:
        wmi = WorldModelInterface(open_bus(args.url), "cli", timeout=args.timeout)
        c = args.wm_command
        if c == "get":
            e = wmi.get_element(args.id)
            print(json.dumps(element_dict(e), indent=2)) if args.json else print_element(e)
        elif c == "query":
            found = wmi.resolve_elements(Element(args.type or "", args.label))
            if args.json:
                print(json.dumps([element_dict(e) for e in found], indent=2))
            else:
                for e in found:
                    print(f"{e.id}  ({e.type})  label={e.label!r}")
                print(f"{len(found)} element(s) at version {wmi.version}")
        elif c == "load":
            report = (wmi.load_scene(name=args.file) if args.on_server else wmi.load_scene(args.file))
            print(f"loaded {args.file}: version {wmi.version}, {len(wmi.get_elements())} elements"
                  + (f"\nnotes: {report}" if report else ""))
        elif c == "save":
            wmi.save_scene(args.file)
            print(f"saved version {wmi.version} to {args.file}")
        elif c == "tree":
            print(json.dumps(containment_tree(wmi), indent=2)) if args.json else print_tree(wmi)
        return 0
    except BrokenPipeError:
        raise  # the reader went away (skillbus wm tree | head): not an error of the world model
    except (WorldModelError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
