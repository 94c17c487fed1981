"""Scene files on the Python side: the world model's Turtle scene is generated from the
same file as the physics server's world."""

import json

import pytest

from skillbus import paths
from skillbus.sim import scene


def test_the_committed_demo_ttl_is_generated_from_the_demo_scene():
    generated = scene.to_turtle(scene.load(paths.demo_scene()))
    committed = (paths.REPO_ROOT / "deploy" / "scenes" / "demo.ttl").read_text()
    assert committed == generated, "regenerate: skillbus scene turtle deploy/scenes/demo.scene.json -o deploy/scenes/demo.ttl"


def test_positions_become_relative_to_the_containing_fixture():
    # a table turned 90 degrees about z at (1, 0, 0); an object 0.2 m further along world y
    s = 2 ** -0.5
    p = scene.relative_pose([1, 0, 0, 0, 0, s, s], [1, 0.2, 0.5, 0, 0, 0, 1])
    assert p[:3] == pytest.approx([0.2, 0.0, 0.5])   # world +y is the table's +x
    assert p[3:] == pytest.approx([0, 0, -s, s])     # and the object is turned back


def test_mistakes_are_named(tmp_path):
    f = tmp_path / "s.json"
    f.write_text(json.dumps({"robot": {"name": "r"}, "fixtures": [{"name": "t"}],
                             "objects": [{"name": "c", "on": "shelf"}]}))
    with pytest.raises(scene.SceneError, match=r"objects\[0\].on names 'shelf', which is not a fixture"):
        scene.load(f)
    f.write_text(json.dumps({"robot": {"name": "r"}, "objects": [{"name": "c", "pose": [0, 0, 0]}]}))
    with pytest.raises(scene.SceneError, match=r"objects\[0\].pose must be 7 numbers"):
        scene.load(f)
    f.write_text("{")
    with pytest.raises(scene.SceneError):
        scene.load(f)
