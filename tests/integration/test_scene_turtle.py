"""`skillbus scene turtle` writes Turtle that the world model server loads, whatever a
label holds: quotes, backslashes and new lines reach the world model unchanged (the
labels are escaped by the world model's own Turtle writer)."""

from __future__ import annotations

import json
import subprocess
import sys

from skillbus import paths
from skillbus.sim import scene
from test_skills import cli

LABELS = {
    "red": 'the "red" cube',
    "green": "back\\slash \\\" and a quote",
    "blue": 'two\nlines, a tab\tand """three quotes"""',
}


def test_labels_with_quotes_reach_the_world_model_unchanged(sandbox, tmp_path):
    doc = json.loads(paths.demo_scene().read_text())
    for o in doc["objects"]:
        o["name"] = LABELS[o["name"]]
    doc["name"] = 'a "quoted" scene\\'
    doc["robot"]["gripper"] = '"gripper"'
    f = scene.save(doc, tmp_path / "quotes.scene.json", paths.demo_scene())
    ttl = tmp_path / "quotes.ttl"
    r = subprocess.run([sys.executable, "-m", "skillbus.cli", "scene", "turtle", str(f), "-o", str(ttl)],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    wm = sandbox.start("wm", [paths.binary("wm_server"), "--wall-clock", "--data", tmp_path / "data",
                              "--scene", ttl])
    rc, out, err = cli(sandbox, "wm", "tree", "--json")
    assert rc == 0, (err, wm.stderr()[-2000:])
    labels: dict[str, str] = {}

    def walk(n):
        labels[n["id"]] = n["label"]
        for c in n["children"]:
            walk(c)

    for root in json.loads(out):
        walk(root)
    assert labels["skiros:Scene-0"] == doc["name"]
    assert [labels[f"skiros:Cube-{i}"] for i in (2, 3, 4)] == list(LABELS.values())
    assert labels["skiros:Gripper-7"] == '"gripper"'
    assert labels["skiros:Table-1"] == "table"
    assert wm.returncode is None, wm.stderr()[-2000:]
