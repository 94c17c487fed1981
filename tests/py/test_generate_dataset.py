"""skillbus generate's parts without running episodes: the randomized scene, the rows
read from a real LCM log file (written here with lcm.EventLog), and the LeRobot dataset
they make, loaded back with Hugging Face `datasets` (the reader LeRobotDataset uses)."""

from __future__ import annotations

import json

import pytest

from skillbus.generate.config import ConfigError, episode_seed
from skillbus.generate.lerobot import DatasetWriter
from skillbus.generate.randomize import randomized
from skillbus.generate.record import RecordError, read

SCENE = {"objects": [{"name": "red", "shape": "box", "size": [0.05, 0.05, 0.05], "pose": [0.4, 0.0, 0.425, 0, 0, 0, 1]},
                     {"name": "green", "shape": "cylinder", "size": [0.03, 0.1], "pose": [0.5, 0.0, 0.45, 0, 0, 0, 1]}],
         "articulated": [{"name": "cabinet", "pose": [0.1, -0.55, 0, 0, 0, 0.7071068, 0.7071068]}]}
SPEC = {"objects": {"red": {"x": [0.4, 0.5], "y": [0.0, 0.2], "yaw": [-0.5, 0.5], "size": [0.04, 0.06],
                            "colors": ["red", "blue"]}},
        "articulated": {"cabinet": {"x": [-0.02, 0.02]}}}


def test_a_seed_gives_one_scene_and_another_seed_another():
    a, info_a = randomized(SCENE, SPEC, episode_seed(1, 0))
    b, _ = randomized(SCENE, SPEC, episode_seed(1, 0))
    c, _ = randomized(SCENE, SPEC, episode_seed(1, 1))
    assert a == b and a != c
    red = a["objects"][0]
    assert 0.4 <= red["pose"][0] <= 0.5 and 0.0 <= red["pose"][1] <= 0.2
    side = red["size"][0]
    assert 0.04 <= side <= 0.06 and red["pose"][2] == pytest.approx(0.4 + side / 2)  # its bottom stays on the table
    assert red["color"] in ("red", "blue") and info_a["objects"]["red"]["color"] == red["color"]
    assert abs(a["articulated"][0]["pose"][0] - 0.1) <= 0.02
    assert SCENE["objects"][0]["pose"][0] == 0.4  # the base scene is untouched


def test_randomization_mistakes_are_named():
    with pytest.raises(ConfigError, match="randomize.objects.blue: the scene has no object 'blue'"):
        randomized(SCENE, {"objects": {"blue": {"x": [0, 1]}}}, 1)
    with pytest.raises(ConfigError, match="randomize.objects.red.x must be \\[lo, hi\\]"):
        randomized(SCENE, {"objects": {"red": {"x": [1, 0]}}}, 1)
    with pytest.raises(ConfigError, match="only boxes can be resized"):
        randomized(SCENE, {"objects": {"green": {"size": [0.02, 0.03]}}}, 1)


def cloud(frame: int, capture: int, z: float):
    """One capture of a 4 x 3 depth camera in one part, every pixel `z` m away but the first
    (no return)."""
    import numpy as np
    from skillbus.msgs import camera_cloud_t, header_t
    m = camera_cloud_t()
    m.header = header_t()
    m.header.frame = frame
    m.camera, m.request_id, m.capture, m.error = "overhead", "", capture, ""
    m.width, m.height = 4, 3
    m.intrinsics, m.range, m.pose = [4.0, 4.0, 1.5, 1.0], [0.05, 3.0], [0, 0, 1, 1, 0, 0, 0]
    m.part, m.num_parts, m.row_start, m.num_rows = 0, 1, 0, 3
    pts = np.zeros((3, 4, 3), dtype="<f4")
    pts[:, :, 2] = z
    pts[0, 0, :] = np.nan
    m.points = pts.tobytes()
    m.num_bytes = len(m.points)
    m.robot_mask = bytes(2)
    m.num_mask_bytes = 2
    return m


def write_log(path, frames, skip=(), clouds=()):
    import lcm
    from skillbus.msgs import articulated_joint_t, articulation_state_t, header_t, sim_object_t, sim_state_t
    log = lcm.EventLog(str(path), "w", overwrite=True)
    for f in frames:
        if f in skip:
            continue
        s = sim_state_t()
        s.header = header_t()
        s.header.frame = f
        s.joint_names = ["joint1", "joint2", "finger_left_joint", "finger_right_joint"]
        s.num_joints = 4
        s.position = [0.01 * f, -0.01 * f, 0.02, 0.02]
        s.velocity = [0.5, -0.5, 0.0, 0.0]
        s.effort = [0.0] * 4
        s.tool_pose = [0.3, 0.0, 0.5, 0, 1, 0, 0]
        s.finger_width, s.finger_width_target = 0.04, 0.0
        o = sim_object_t()
        o.name, o.pose, o.twist = "red", [0.4, 0.0, 0.425 + 0.001 * f, 0, 0, 0, 1], [0.0] * 6
        s.objects, s.num_objects = [o], 1
        s.contacts, s.num_contacts = [], 0
        log.write_event(f * 1000, "SB_SIM_STATE", s.encode())
        a = articulation_state_t()
        a.header = header_t()
        a.header.frame = f
        j = articulated_joint_t()
        j.object, j.joint, j.concept, j.kind = "cabinet", "drawer_joint", "Drawer", "prismatic"
        j.position, j.lower, j.upper = 0.001 * f, 0.0, 0.25
        j.axis, j.origin, j.handle_pose = [0, 1, 0], [0, 0, 0], [0, 0, 0, 0, 0, 0, 1]
        a.joints, a.num_joints = [j], 1
        log.write_event(f * 1000 + 1, "SB_ROBOT_ARTICULATION", a.encode())
        for c in clouds:
            if c.header.frame == f:
                log.write_event(f * 1000 + 2, "SB_CAMERA_CLOUD", c.encode())
    log.close()


def test_rows_come_from_the_frames_and_a_lost_frame_refuses_the_episode(tmp_path):
    log = tmp_path / "e.lcmlog"
    write_log(log, range(100, 121))
    ep = read(log, stride=5, frame_ms=20.0)
    assert [r["frame"] for r in ep.rows] == [100, 105, 110, 115, 120] and ep.frames == 21
    assert ep.names["observation.state"] == ["joint1", "joint2", "gripper_width"]
    r0, r1 = ep.rows[0], ep.rows[1]
    assert r0["timestamp"] == 0.0 and r1["timestamp"] == pytest.approx(0.1)
    assert r0["observation.state"] == pytest.approx([1.0, -1.0, 0.04])
    assert r0["action"] == pytest.approx([1.05, -1.05, 0.0])  # the next row's joints, the commanded width
    assert r0["observation.articulation"] == pytest.approx([0.1])
    write_log(log, range(100, 121), skip={107})
    with pytest.raises(RecordError, match="1 frame\\(s\\) is missing \\(first 107\\)"):
        read(log, stride=5, frame_ms=20.0)


def an_episode_and_a_writer(tmp_path):
    """An episode of 10 rows (50 frames, every 5th) and a writer of a new dataset folder."""
    log = tmp_path / "e.lcmlog"
    write_log(log, range(0, 50))
    root = tmp_path / "ds"
    return read(log, stride=5, frame_ms=20.0), root, DatasetWriter(root, fps=10)


def test_the_dataset_loads_with_hugging_face_datasets_and_appends_in_order(tmp_path):
    import datasets
    ep, root, w = an_episode_and_a_writer(tmp_path)
    w.write_episode(ep, "put the cube away", {"seed": 1, "success": True, "session_digest": "ab"})
    w.write_episode(ep, "put the cube away", {"seed": 2, "success": False, "failure_reason": "slipped"})
    w2 = DatasetWriter(root, fps=10)  # a later run appends
    w2.write_episode(ep, "open the drawer", {"seed": 3, "success": True})
    info = json.loads((root / "meta" / "info.json").read_text())
    assert info["codebase_version"] == "v2.1" and info["total_episodes"] == 3 and info["total_frames"] == 30
    assert info["total_tasks"] == 2 and info["features"]["observation.state"]["shape"] == [3]
    files = sorted(str(p) for p in (root / "data").rglob("*.parquet"))
    assert [p.rsplit("/", 1)[1] for p in files] == [f"episode_00000{i}.parquet" for i in range(3)]
    ds = datasets.load_dataset("parquet", data_files=files, split="train", cache_dir=str(tmp_path / "hf"))
    assert len(ds) == 30 and ds["index"] == list(range(30))
    assert ds["episode_index"] == [0] * 10 + [1] * 10 + [2] * 10 and ds["task_index"][-1] == 1
    assert ds["next.success"][:10] == [True] * 10 and ds["next.success"][10:20] == [False] * 10
    assert ds["next.done"][9] and not ds["next.done"][8]
    assert len(ds[0]["observation.object_poses"]) == 7
    episodes = [json.loads(x) for x in (root / "meta" / "episodes.jsonl").read_text().splitlines()]
    assert [e["seed"] for e in episodes] == [1, 2, 3] and episodes[1]["failure_reason"] == "slipped"
    assert not list(root.rglob("*.tmp"))


def test_ctrl_c_while_an_episode_is_written_comes_after_the_episode_is_whole(tmp_path, monkeypatch):
    import os
    import signal
    import pyarrow.parquet
    ep, root, w = an_episode_and_a_writer(tmp_path)
    real_write = pyarrow.parquet.write_table

    def write_then_ctrl_c(table, where, **kw):
        real_write(table, where, **kw)
        os.kill(os.getpid(), signal.SIGINT)  # between the file's write and its rename

    monkeypatch.setattr(pyarrow.parquet, "write_table", write_then_ctrl_c)
    with pytest.raises(KeyboardInterrupt):
        w.write_episode(ep, "put the cube away", {"seed": 1, "success": True})
    assert [p.name for p in (root / "data").rglob("*")] == ["chunk-000", "episode_000000.parquet"]
    assert len((root / "meta" / "episodes.jsonl").read_text().splitlines()) == 1
    assert len((root / "meta" / "episodes_stats.jsonl").read_text().splitlines()) == 1
    assert json.loads((root / "meta" / "info.json").read_text())["total_episodes"] == 1
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # given back


def test_what_a_writer_killed_mid_episode_left_is_removed_on_open(tmp_path):
    ep, root, w = an_episode_and_a_writer(tmp_path)
    w.write_episode(ep, "put the cube away", {"seed": 1, "success": True})
    chunk = root / "data" / "chunk-000"
    # kill -9 between the rename and the meta lines, and another one mid-file:
    (chunk / "episode_000001.parquet").write_bytes((chunk / "episode_000000.parquet").read_bytes())
    (chunk / "episode_000002.parquet.tmp").write_bytes(b"PAR1 cut")
    stats = root / "meta" / "episodes_stats.jsonl"
    stats.write_text(stats.read_text() + json.dumps({"episode_index": 1, "stats": {}}) + "\n")
    w2 = DatasetWriter(root, fps=10)
    assert sorted(p.name for p in chunk.iterdir()) == ["episode_000000.parquet"]
    assert [json.loads(x)["episode_index"] for x in stats.read_text().splitlines()] == [0]
    assert w2.write_episode(ep, "put the cube away", {"seed": 2, "success": True}) == 1
    assert sorted(p.name for p in chunk.iterdir()) == ["episode_000000.parquet", "episode_000001.parquet"]


def test_a_line_cut_by_a_killed_writer_is_dropped_with_its_episode(tmp_path):
    # Before, a cut last line of episodes.jsonl (kill -9 or a power loss in its write)
    # stopped every later run with a JSONDecodeError traceback.
    ep, root, w = an_episode_and_a_writer(tmp_path)
    w.write_episode(ep, "put the cube away", {"seed": 1, "success": True})
    w.write_episode(ep, "put the cube away", {"seed": 2, "success": True})
    meta = root / "meta" / "episodes.jsonl"
    lines = meta.read_text().splitlines()
    meta.write_text(lines[0] + "\n" + lines[1][: len(lines[1]) // 2])  # the second line cut
    w2 = DatasetWriter(root, fps=10)
    assert [e["episode_index"] for e in w2.episodes] == [0]
    assert meta.read_text() == lines[0] + "\n"
    chunk = root / "data" / "chunk-000"
    assert sorted(p.name for p in chunk.iterdir()) == ["episode_000000.parquet"]
    stats = root / "meta" / "episodes_stats.jsonl"
    assert [json.loads(x)["episode_index"] for x in stats.read_text().splitlines()] == [0]
    assert w2.write_episode(ep, "put the cube away", {"seed": 3, "success": True}) == 1
    meta.write_text("{not json}\n" + meta.read_text())  # damage that is no cut: named, not guessed
    with pytest.raises(ValueError, match=r"episodes.jsonl, line 1: not JSON"):
        DatasetWriter(root, fps=10)


def test_a_depth_camera_is_recorded_as_its_latest_whole_capture(tmp_path):
    log = tmp_path / "e.lcmlog"
    write_log(log, range(0, 30), clouds=[cloud(3, 0, 1.2), cloud(13, 1, 0.8)])
    ep = read(log, stride=5, frame_ms=20.0)
    assert ep.shapes == {"observation.depth.overhead": [3, 4]}
    depth = [r["observation.depth.overhead"] for r in ep.rows]  # rows at frames 0 5 10 15 20 25
    assert depth[0] == [0.0] * 12  # before the first capture
    assert depth[1] == pytest.approx([0.0] + [1.2] * 11) and depth[2] == depth[1]  # no return: 0
    assert depth[3] == pytest.approx([0.0] + [0.8] * 11)
    root = tmp_path / "ds"
    DatasetWriter(root, fps=10).write_episode(ep, "look", {"success": True})
    info = json.loads((root / "meta" / "info.json").read_text())
    assert info["features"]["observation.depth.overhead"]["shape"] == [3, 4]
    import datasets
    ds = datasets.load_dataset("parquet", data_files=[str(p) for p in (root / "data").rglob("*.parquet")],
                               split="train", cache_dir=str(tmp_path / "hf"))
    assert ds[3]["observation.depth.overhead"][1] == pytest.approx(0.8)
    # a capture that lost a part refuses the episode
    part = cloud(13, 1, 0.8)
    part.num_parts, part.num_rows = 2, 2
    part.points = part.points[: 2 * 4 * 12]
    part.num_bytes = len(part.points)
    part.robot_mask, part.num_mask_bytes = bytes(1), 1
    write_log(log, range(0, 30), clouds=[cloud(3, 0, 1.2), part])
    with pytest.raises(RecordError, match="camera overhead: 1 capture\\(s\\) lost parts"):
        read(log, stride=5, frame_ms=20.0)


def test_one_articulated_object_is_kept_per_episode():
    scene = {"objects": [], "articulated": [{"name": "cabinet", "pose": [0, -0.55, 0, 0, 0, 0, 1]},
                                            {"name": "cupboard", "pose": [0, 0.55, 0, 0, 0, 0, 1]},
                                            {"name": "fridge", "pose": [1, 0, 0, 0, 0, 0, 1]}]}
    spec = {"choose_articulated": ["cabinet", "cupboard"], "articulated": {"cupboard": {"x": [0.1, 0.1]}}}
    kept = set()
    for seed in range(20):
        doc, info = randomized(scene, spec, episode_seed(4, seed))
        names = [a["name"] for a in doc["articulated"]]
        assert len(names) == 2 and "fridge" in names  # one of the two, and what is not in the choice
        kept.add(info["articulated_chosen"])
        if info["articulated_chosen"] == "cupboard":
            assert doc["articulated"][0]["pose"][0] == pytest.approx(0.1)
    assert kept == {"cabinet", "cupboard"}
    with pytest.raises(ConfigError, match="no articulated object 'shed'"):
        randomized(scene, {"choose_articulated": ["shed"]}, 1)


@pytest.mark.parametrize("extra,why", [
    ("fps: 30\n", "fps 30 is not a whole number of 20 ms frames per row: rows come every whole frame (50, 25, 16.6667"),
    ("frame_ms: 30\n", "frame_ms 30 does not divide the skill manager's tick of 40 ms"),
    ("frame_ms: 5\n", "frame_ms 5 is not a whole number of the scene's physics steps (2 ms)"),
])
def test_frames_and_rows_that_do_not_fit_are_refused_before_any_episode(tmp_path, extra, why):
    # Before: fps 30 wrote rows every 40 ms into a dataset that said 30 fps; frames of
    # 30 ms made skills tick every 120 ms; 5 ms frames broke every episode in the physics.
    from skillbus import paths
    from skillbus.generate import config
    base = paths.REPO_ROOT / "deploy" / "generate" / "pick_place.yaml"
    text = "\n".join(line for line in base.read_text().splitlines() if not line.startswith(("fps:", "frame_ms:")))
    text = text.replace("../", str(base.parent.parent) + "/")  # (the scene and task beside the original)
    (cfg := tmp_path / "c.yaml").write_text(text + "\n" + extra)
    with pytest.raises(ConfigError) as e:
        config.load(cfg)
    assert why in str(e.value), str(e.value)
    (ok := tmp_path / "ok.yaml").write_text(text + "\nfps: 25\nframe_ms: 20\n")
    assert config.load(ok).fps == 25.0


def test_generate_names_a_damaged_dataset_before_it_runs_an_episode(tmp_path):
    # Before: a JSONDecodeError traceback (and, for a refusal mid-run, workers left running).
    import subprocess
    import sys
    from skillbus import paths
    (tmp_path / "out" / "meta").mkdir(parents=True)
    (tmp_path / "out" / "meta" / "episodes.jsonl").write_text("{damaged\n{\"episode_index\": 0}\n")
    r = subprocess.run([sys.executable, "-m", "skillbus.cli", "generate",
                        str(paths.REPO_ROOT / "deploy" / "generate" / "pick_place.yaml"), "--episodes", "1",
                        "--seed", "1", "--out", str(tmp_path / "out")], capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, r.stderr[-2000:]
    assert f"error: the dataset {tmp_path / 'out'}: " in r.stderr and "episodes.jsonl, line 1: not JSON" in r.stderr
    assert "Traceback" not in r.stderr
