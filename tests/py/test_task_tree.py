"""skillbus.skill.task_tree: the latest tree of each task and what each progress changed
(the console's and `skillbus run --watch`'s source), and the terminal's change lines."""

import io
import contextlib

from skillbus.msgs import skill_node_progress_t, skill_progress_t
from skillbus.skill.cli import ChangePrinter
from skillbus.skill.task_tree import TaskTrees, change_lines, node_path


def node(i, parent, state="Running", message="", type_=None, processor=""):
    return {"id": i, "parent": parent, "type": f"S{i}" if type_ is None else type_, "label": "",
            "processor": processor, "state": state, "message": message, "code": 0, "progress": 0.0, "params": {}}


def progress(task, tick, state, nodes):
    return {"task": task, "tick": tick, "state": state, "nodes": nodes}


def test_changes_name_only_the_nodes_that_differ_and_a_shrunk_tree_says_its_size():
    trees = TaskTrees()
    first = trees.apply("r1", progress(1, 1, "Running", [node(0, -1), node(1, 0), node(2, 1)]))
    assert first.new and sorted(first.nodes) == [0, 1, 2] and first.count == 3
    later = trees.apply("r1", progress(1, 2, "Running", [node(0, -1), node(1, 0), node(2, 1)]))
    assert later.nodes == {} and later.tick == 2  # only the tick moved (a primitive idle): a page shows it
    same = trees.apply("r1", progress(1, 2, "Running", [node(0, -1), node(1, 0), node(2, 1)]))
    assert same is None  # nothing changed: nothing to send
    shrunk = trees.apply("r1", progress(1, 3, "Running", [node(0, -1), node(1, 0, "Success")]))
    assert sorted(shrunk.nodes) == [1] and shrunk.count == 2 and not shrunk.new
    assert trees.get("r1", 1).nodes == [node(0, -1), node(1, 0, "Success")]
    assert trees.get("r2", 1) is None  # tasks are per robot: r2's task 1 is another task


def test_a_final_tree_is_kept_and_older_or_later_trees_change_nothing():
    trees = TaskTrees()
    trees.apply("", progress(4, 5, "Running", [node(0, -1)]))
    assert trees.apply("", progress(4, 3, "Running", [node(0, -1, "Idle")])) is None  # older: a crossed catch-up
    end = trees.apply("", progress(4, 6, "Success", [node(0, -1, "Success", "done")]))
    assert end.ended and end.state == "Success"
    assert trees.apply("", progress(4, 7, "Running", [node(0, -1)])) is None  # nothing after the end
    assert trees.get("", 4).state == "Success" and trees.running() == []


def test_at_most_keep_finished_ended_tasks_are_kept_the_oldest_going_first():
    trees = TaskTrees(keep_finished=2)
    for t in (1, 2, 3):
        trees.apply("", progress(t, 1, "Failure", [node(0, -1, "Failure")]))
    trees.apply("", progress(9, 1, "Running", [node(0, -1)]))
    assert sorted(k[1] for k in trees.trees) == [2, 3, 9]


def test_change_lines_name_each_node_by_its_path():
    trees = TaskTrees()
    nodes = [node(0, -1, type_="ClearTable"), node(1, 0, type_="", processor="Sequential"),
             node(2, 1, "Success", "gripped", type_="Grasp")]
    c = trees.apply("", progress(1, 1, "Running", nodes))
    assert node_path(nodes, 2) == "ClearTable / (Sequential) / Grasp"
    assert change_lines(trees.get("", 1), c)[-1] == "  ClearTable / (Sequential) / Grasp  Success: gripped"


def _msg(tick, states):
    p = skill_progress_t()
    p.task, p.tick, p.state = 1, tick, 1
    for i, (state, message) in enumerate(states):
        n = skill_node_progress_t()
        n.id, n.parent, n.type, n.state, n.message = i, i - 1, f"N{i}", state, message
        p.nodes.append(n)
    p.num_nodes = len(p.nodes)
    return p


def test_watch_prints_only_nodes_whose_state_or_message_changed():
    printer = ChangePrinter()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        printer.print(_msg(1, [(2, ""), (2, "moving")]))
        printer.print(_msg(2, [(2, ""), (2, "moving")]))   # the same: nothing
        printer.print(_msg(3, [(2, ""), (3, "there")]))    # one node
    lines = out.getvalue().splitlines()
    assert lines == ["--- task 1, tick 1", "N0 Running", "N0 / N1 Running: moving",
                     "--- task 1, tick 3", "N0 / N1 Success: there"], lines
