"""Scene files on the Python side: the world model's Turtle scene is generated from the
same file as the physics server's world, and both are read and checked by one reader
(sb_scene, the physics server's C++ reader), so Python accepts exactly what the physics
server accepts and names a mistake the same way."""

import json
import math
import subprocess
import sys

import pytest

from skillbus import paths
from skillbus.sim import scene


@pytest.mark.parametrize("name", ["demo", "two_arms"])
def test_the_committed_ttl_is_generated_from_its_scene(name):
    scenes = paths.REPO_ROOT / "deploy" / "scenes"
    generated = scene.to_turtle(scene.load(scenes / f"{name}.scene.json"))
    committed = (scenes / f"{name}.ttl").read_text()
    assert committed == generated, (f"regenerate: skillbus scene turtle deploy/scenes/{name}.scene.json "
                                    f"-o deploy/scenes/{name}.ttl")


def test_two_robots_each_with_their_ids_after_everything_else():
    ids = scene.element_ids(paths.REPO_ROOT / "deploy" / "scenes" / "two_arms.scene.json")
    assert ids["r1"] == "skiros:Robot-11" and ids["r2_gripper"] == "skiros:Gripper-15" and ids["bin2"] == "skiros:Bin-10"
    assert list(ids)[-6:] == ["r1", "r1_gripper", "r1_arm", "r2", "r2_gripper", "r2_arm"]
    one = scene.element_ids(paths.demo_scene())  # one robot: the ids it always had
    assert one["arm_robot"] == "skiros:Robot-6" and one["gripper"] == "skiros:Gripper-7" and one["arm"] == "skiros:Arm-8"


def test_positions_become_relative_to_the_containing_fixture():
    # a table turned 90 degrees about z at (1, 0, 0); an object 0.2 m further along world y
    s = 2 ** -0.5
    p = scene.relative_pose([1, 0, 0, 0, 0, s, s], [1, 0.2, 0.5, 0, 0, 0, 1])
    assert p[:3] == pytest.approx([0.2, 0.0, 0.5])   # world +y is the table's +x
    assert p[3:] == pytest.approx([0, 0, -s, s])     # and the object is turned back


def demo_doc() -> dict:
    return json.loads(paths.demo_scene().read_text())


def refused(tmp_path, doc) -> str:
    f = tmp_path / "s.scene.json"
    if isinstance(doc, str):
        f.write_text(doc)
    else:
        scene.save(doc, f, paths.demo_scene())
    with pytest.raises(scene.SceneError) as e:
        scene.load(f)
    message = str(e.value)
    assert message.startswith(f"{f}: "), message  # the file, then the field
    return message[len(f"{f}: "):]


def test_mistakes_are_named_with_their_field(tmp_path):
    d = demo_doc()
    del d["objects"][0]["size"]
    assert refused(tmp_path, d) == "objects[0].size is missing"           # was a KeyError traceback
    d = demo_doc()
    d["objects"][1]["mass"] = -0.2
    assert refused(tmp_path, d) == "objects[1].mass must be > 0"          # was accepted
    d = demo_doc()
    d["objects"][0]["on"] = "shelf"
    assert refused(tmp_path, d) == ("objects[0].on names 'shelf', which is not a fixture "
                                    "(objects do not start on obstacles)")
    d = demo_doc()
    d["objects"][0]["on"] = "post"
    assert refused(tmp_path, d).startswith("objects[0].on names 'post', which is not a fixture")
    d = demo_doc()
    d["obstacles"][0]["name"] = "bin"
    assert refused(tmp_path, d) == "obstacles[0].name 'bin' is used twice in the scene"
    d = demo_doc()
    del d["obstacles"][0]["urdf"]
    assert refused(tmp_path, d) == "obstacles[0].urdf is missing"
    d = demo_doc()
    d["objects"][2]["pose"] = [0, 0, 0]
    assert refused(tmp_path, d) == "objects[2].pose must be an array of 7 numbers"
    d = demo_doc()
    d["fixtures"][1]["name"] = "table"
    assert refused(tmp_path, d) == "fixtures[1].name 'table' is used twice in the scene"
    d = demo_doc()
    d["objects"][0]["type"] = "Red Cube"
    assert refused(tmp_path, d).startswith("objects[0].type must be a concept name")
    d = demo_doc()
    del d["robot"]
    assert refused(tmp_path, d) == "robot is missing (or robots, for several)"
    assert refused(tmp_path, "{").startswith("not valid JSON: ")
    with pytest.raises(scene.SceneError, match=r"cannot open the scene file"):
        scene.load(tmp_path / "none.scene.json")


def test_load_gives_the_scene_normalized():
    s = scene.load(paths.demo_scene())
    assert s["robot"]["urdf"] == str(paths.REPO_ROOT / "sim_server" / "models" / "arm6.urdf")  # absolute
    assert s["physics"]["lcp_solver"] == "dantzig"  # a default filled in
    assert [o["name"] for o in s["objects"]] == ["red", "green", "blue"]
    assert s["objects"][0]["pose"] == [0.4, 0.15, 0.425, 0.0, 0.0, 0.0, 1.0]


def test_defaults_and_a_quaternion_normalized(tmp_path):
    d = demo_doc()
    d["objects"] = [{"name": "can", "shape": "cylinder", "radius": 0.03, "height": 0.1, "pose": [0, 0, 0.05, 0, 0, 2, 2]}]
    f = scene.save(d, tmp_path / "can.scene.json", paths.demo_scene())
    can = scene.load(f)["objects"][0]
    assert can["type"] == "Product" and can["mass"] == 0.1 and can["friction"] == 0.8 and "on" not in can
    assert can["pose"][3:] == pytest.approx([0, 0, 2 ** -0.5, 2 ** -0.5])


def test_obstacles_are_numbered_after_the_robots():
    """An obstacle added to a scene renumbers nothing: the skills' task names the robot's
    gripper and arm by id (skiros:Gripper-7), which stays."""
    s = scene.load(paths.demo_scene())
    assert s["obstacles"] == [{"name": "post", "type": "Obstacle", "urdf": str(paths.REPO_ROOT / "sim_server" / "models" / "post.urdf"),
                               "pose": [0.3, 0.5, 0.0, 0.0, 0.0, 0.0, 1.0], "friction": 0.8}]
    ttl = scene.to_turtle(s)
    assert "skiros:Gripper-7\n" in ttl and "skiros:Arm-8\n" in ttl
    assert "skiros:Obstacle-9\n\ta skiros:Obstacle ,\n\t\towl:NamedIndividual ;\n\trdfs:label \"post\"" in ttl
    del s["obstacles"]
    assert "Obstacle" not in scene.to_turtle(s) and "skiros:Gripper-7\n" in scene.to_turtle(s)


def test_a_changed_document_is_numbered_again():
    belief = scene.load(paths.demo_scene())
    belief["objects"] = [o for o in belief["objects"] if o["name"] != "green"]
    ttl = scene.to_turtle(belief)
    assert "skiros:Cube-3\n\ta skiros:Cube ,\n\t\towl:NamedIndividual ;\n\trdfs:label \"blue\"" in ttl
    assert "skiros:Robot-5\n" in ttl and "green" not in ttl


def skillbus_scene(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "skillbus.cli", "scene", *args], capture_output=True, text=True,
                          timeout=60)


def test_the_command_line_checks_and_names_the_field(tmp_path):
    r = skillbus_scene("check", str(paths.demo_scene()))
    assert r.returncode == 0 and "a valid scene ('demo': robot 'arm_robot', 2 fixture(s), 1 obstacle(s), 3 object(s))" in r.stdout
    d = demo_doc()
    del d["objects"][0]["size"]
    f = scene.save(d, tmp_path / "nosize.scene.json", paths.demo_scene())
    for action in ("check", "turtle"):
        r = skillbus_scene(action, str(f))
        assert r.returncode == 2 and r.stderr == f"error: {f}: objects[0].size is missing\n", r.stderr
        assert r.stdout == ""


def scattered(tmp_path, name: str = "s", **scatter) -> list[dict]:
    d = demo_doc()
    d["scatter"] = {"on": "table", "region": [0.3, -0.25, 0.65, 0.3], "min_gap": 0.1, "seed": 1, **scatter}
    return scene.load(scene.save(d, tmp_path / f"{name}.scene.json", paths.demo_scene()))["objects"]


def test_scatter_puts_the_objects_at_seeded_random_places_of_its_region(tmp_path):
    one, again, other = scattered(tmp_path, "a"), scattered(tmp_path, "b"), scattered(tmp_path, "c", seed=2)
    assert one == again                       # the same seed: the same poses, bit for bit
    assert [o["pose"] for o in one] != [o["pose"] for o in other]
    fixed = {o["name"]: o["pose"] for o in demo_doc()["objects"]}
    for objects in (one, other):
        for o in objects:
            x, y, z = o["pose"][:3]
            assert 0.3 <= x <= 0.65 and -0.25 <= y <= 0.3 and z == 0.425, o
            assert o["pose"][:2] != fixed[o["name"]][:2]
            assert math.isclose(sum(c * c for c in o["pose"][3:]), 1.0, abs_tol=1e-9)
            assert o["pose"][3] == 0 and o["pose"][4] == 0  # turned about z only
        for i, a in enumerate(objects):
            for b in objects[i + 1:]:
                assert math.dist(a["pose"][:2], b["pose"][:2]) >= 0.1
    # The world model's Turtle carries the same poses (table-relative: the table is at x 0.5).
    ttl = scene.to_turtle(scene.load(tmp_path / "a.scene.json"))
    assert f'rdfs:label "red" ;\n\tskiros:PositionX "{round(one[0]["pose"][0] - 0.5, 6):g}"' in ttl
    assert scattered(tmp_path, "d", yaw=False)[0]["pose"][3:] == [0.0, 0.0, 0.0, 1.0]


def test_scatter_mistakes_are_named(tmp_path):
    d = demo_doc()
    for bad, message in (({"on": "post", "region": [0, 0, 1, 1]}, "scatter.on names 'post', which is not a fixture"),
                         ({"on": "table"}, "scatter.region is missing"),
                         ({"on": "table", "region": [1, 0, 0, 1]}, "scatter.region must be [x_min, y_min, x_max, y_max] with max > min"),
                         ({"on": "table", "region": [0, 0, 1, 1], "seed": -1}, "scatter.seed must be a whole number from 0 to 4294967295"),
                         ({"on": "table", "region": [0, 0, 1, 1], "yaw": "yes"}, "scatter.yaw must be true or false"),
                         ({"on": "table", "region": [0, 0, 0.05, 0.05], "min_gap": 0.1},
                          "scatter cannot place 2 objects 0.100000 m apart in its region (a larger region or a smaller min_gap)")):
        d["scatter"] = bad
        assert refused(tmp_path, d) == message
