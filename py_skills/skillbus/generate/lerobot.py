"""A LeRobot dataset (the v2.1 layout) written one episode at a time::

    ROOT/meta/info.json              features, fps, totals, paths
    ROOT/meta/tasks.jsonl            {"task_index", "task"}
    ROOT/meta/episodes.jsonl         {"episode_index", "tasks", "length", + skillbus: seed, digests, success, ...}
    ROOT/meta/episodes_stats.jsonl   per episode, per feature: min, max, mean, std, count
    ROOT/data/chunk-000/episode_000000.parquet

Why LeRobot's layout: one parquet file per episode, so an episode is written whole or
not at all (a temporary file renamed into place, then its line in episodes.jsonl), and
parallel workers never share a file; parquet is columnar and read by every data tool
(pyarrow, pandas, Hugging Face datasets, which LeRobotDataset reads it with).
An episode's row holds the features of skillbus.generate.record plus LeRobot's
``timestamp``, ``frame_index``, ``episode_index``, ``index`` (over the dataset),
``task_index``, ``next.done`` and ``next.success`` (the episode's label, on every row).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from skillbus.generate.uninterrupted import uninterrupted

CHUNK = 1000
DATA_PATH = "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet"
DEPTH = "observation.depth."
VECTORS = ("observation.state", "observation.velocity", "observation.tool_pose", "observation.object_poses",
           "observation.articulation", "action")


def _sync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _sync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _atomic_write(path: Path, text: str) -> None:
    """`path` is the old text or the whole new one, on disk on return (beside, synced,
    renamed, the folder synced): a power loss never leaves a meta file cut."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    _sync_file(tmp)
    os.replace(tmp, path)
    _sync_dir(path.parent)


def _append_line(path: Path, line: dict[str, Any]) -> None:
    with open(path, "a") as f:
        f.write(json.dumps(line) + "\n")
        f.flush()
        os.fsync(f.fileno())


def _episode_index(path: Path) -> int:
    return int(path.stem.rsplit("_", 1)[1])


class DatasetWriter:
    def __init__(self, root: Path, fps: float, robot_type: str = "arm6") -> None:
        self.root, self.fps, self.robot_type = Path(root), fps, robot_type
        (self.root / "meta").mkdir(parents=True, exist_ok=True)
        self.episodes: list[dict[str, Any]] = []
        self.tasks: dict[str, int] = {}
        self.names: dict[str, list[str]] | None = None
        self.shapes: dict[str, list[int]] = {}  # the depth images' [height, width]
        self.total_frames = 0
        for line in self._lines("episodes.jsonl"):  # an earlier run's episodes stay (generate appends)
            self.episodes.append(line)
            self.total_frames += line["length"]
        for line in self._lines("tasks.jsonl"):
            self.tasks[line["task"]] = line["task_index"]
        info = self.root / "meta" / "info.json"
        if info.exists():
            feats = json.loads(info.read_text())["features"]
            self.names = {k: v["names"] for k, v in feats.items() if k in VECTORS or k.startswith(DEPTH)}
            self.shapes = {k: v["shape"] for k, v in feats.items() if k.startswith(DEPTH)}
        self._tidy()

    def _tidy(self) -> None:
        """Removes what a writer killed mid-episode (kill -9, power loss) left: temporary
        files, an episode file whose line never reached episodes.jsonl, and stats lines
        beyond the episodes. The episodes in episodes.jsonl are the dataset."""
        n = len(self.episodes)
        for tmp in self.root.rglob("*.tmp"):
            tmp.unlink()
        for f in (self.root / "data").glob("chunk-*/episode_*.parquet"):
            if _episode_index(f) >= n:
                f.unlink()
        stats_lines = self._lines("episodes_stats.jsonl")
        if len(stats_lines) > n:
            _atomic_write(self.root / "meta" / "episodes_stats.jsonl",
                          "".join(json.dumps(x) + "\n" for x in stats_lines if x["episode_index"] < n))
        if n and self.names is not None:
            self.write_meta()  # its totals from episodes.jsonl again

    def _lines(self, name: str) -> list[dict[str, Any]]:
        """The lines of a meta file; a last line cut by a killed writer (no newline, or not
        JSON) is dropped, and the file rewritten without it. A damaged line before the last
        is a ValueError naming it: that is no cut, and nothing is guessed."""
        p = self.root / "meta" / name
        if not p.exists():
            return []
        text = p.read_text()
        raw = text.split("\n")
        whole, tail = raw[:-1], raw[-1]  # (tail: after the last newline, "" when the file ends with one)
        out = []
        for i, x in enumerate(whole, 1):
            if not x.strip():
                continue
            try:
                out.append(json.loads(x))
            except ValueError:
                if i == len(whole) and not tail:
                    whole = whole[:-1]
                    tail = x  # (a last line cut within its JSON, yet ended: dropped as cut)
                    break
                raise ValueError(f"{p}, line {i}: not JSON ({x[:60]!r}); the dataset needs repair by hand") from None
        if tail.strip():
            _atomic_write(p, "".join(line + "\n" for line in whole if line.strip()))
        return out

    def write_episode(self, episode: Any, task: str, meta: dict[str, Any]) -> int:
        """Writes one episode (skillbus.generate.record.Episode) labelled with `meta`;
        returns its episode_index. Ctrl-C during the write is held until the episode is
        whole, then raised."""
        with uninterrupted():
            return self._write_episode(episode, task, meta)

    def _write_episode(self, episode: Any, task: str, meta: dict[str, Any]) -> int:
        if self.names is not None and self.names != episode.names:
            raise ValueError("this episode's features differ from the dataset's (another scene or robot?)")
        index = len(self.episodes)
        task_index = self.tasks.get(task, len(self.tasks))
        shapes = dict(episode.shapes)
        rows = episode.rows
        n = len(rows)
        success = bool(meta.get("success"))
        cols: dict[str, Any] = {k: pa.array([r[k] for r in rows], type=pa.list_(pa.float32()))
                                for k in VECTORS + tuple(sorted(shapes))}
        cols.update({
            "timestamp": pa.array([r["timestamp"] for r in rows], type=pa.float32()),
            "frame_index": pa.array(range(n), type=pa.int64()),
            "episode_index": pa.array([index] * n, type=pa.int64()),
            "index": pa.array(range(self.total_frames, self.total_frames + n), type=pa.int64()),
            "task_index": pa.array([task_index] * n, type=pa.int64()),
            "next.done": pa.array([i == n - 1 for i in range(n)], type=pa.bool_()),
            "next.success": pa.array([success] * n, type=pa.bool_()),
        })
        path = self.root / DATA_PATH.format(episode_chunk=index // CHUNK, episode_index=index)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".tmp")
        try:
            pq.write_table(pa.table(cols), tmp)
            _sync_file(tmp)
            os.replace(tmp, path)  # whole, or not at all
            _sync_dir(path.parent)
        finally:
            tmp.unlink(missing_ok=True)
        # Only now, with the file on disk, does the writer's state change. The episode's
        # line in episodes.jsonl comes last and makes it part of the dataset: a writer
        # killed before it leaves a file and a stats line that the next open removes.
        self.names, self.shapes, self.tasks[task] = episode.names, shapes, task_index
        line = {"episode_index": index, "tasks": [task], "length": n, **meta}
        _append_line(self.root / "meta" / "episodes_stats.jsonl", {"episode_index": index, "stats": stats(rows)})
        _append_line(self.root / "meta" / "episodes.jsonl", line)
        self.episodes.append(line)
        self.total_frames += n
        self.write_meta()
        return index

    def write_meta(self) -> None:
        names = self.names or {k: [] for k in VECTORS}
        features: dict[str, Any] = {k: {"dtype": "float32", "shape": [len(names[k])], "names": names[k]}
                                    for k in VECTORS}
        features.update({k: {"dtype": "float32", "shape": shape, "names": ["height", "width"],
                             "info": "depth, m along the camera's view (0: no return), row-major"}
                         for k, shape in sorted(self.shapes.items())})
        features.update({k: {"dtype": t, "shape": [1], "names": None} for k, t in (
            ("timestamp", "float32"), ("frame_index", "int64"), ("episode_index", "int64"), ("index", "int64"),
            ("task_index", "int64"), ("next.done", "bool"), ("next.success", "bool"))})
        n = len(self.episodes)
        info = {"codebase_version": "v2.1", "robot_type": self.robot_type, "total_episodes": n,
                "total_frames": self.total_frames, "total_tasks": len(self.tasks), "total_videos": 0,
                "total_chunks": (n - 1) // CHUNK + 1 if n else 0, "chunks_size": CHUNK, "fps": self.fps,
                "splits": {"train": f"0:{n}"}, "data_path": DATA_PATH, "video_path": None, "features": features}
        _atomic_write(self.root / "meta" / "info.json", json.dumps(info, indent=2))
        _atomic_write(self.root / "meta" / "tasks.jsonl",
                      "".join(json.dumps({"task_index": i, "task": t}) + "\n" for t, i in sorted(self.tasks.items(),
                                                                                            key=lambda x: x[1])))


def stats(rows: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k in sorted(k for k in (rows[0] if rows else {}) if k.startswith(DEPTH)):  # one channel: over all pixels
        import numpy as np
        a = np.asarray([r[k] for r in rows], dtype=np.float64)
        out[k] = {"min": [float(a.min())], "max": [float(a.max())], "mean": [float(a.mean())], "std": [float(a.std())],
                  "count": [len(rows)]}
    for k in VECTORS:
        cols = list(zip(*[r[k] for r in rows])) if rows and rows[0][k] else []
        if not cols:
            continue
        out[k] = {"min": [min(c) for c in cols], "max": [max(c) for c in cols],
                  "mean": [sum(c) / len(c) for c in cols],
                  "std": [math.sqrt(max(0.0, sum(x * x for x in c) / len(c) - (sum(c) / len(c)) ** 2)) for c in cols],
                  "count": [len(rows)]}
    return out
