"""The demo's real-time factor before and after obstacle-avoiding motion (issue
"Perception"), in one run: ClearTable on the demo scene without its post (the motions as
they were: every joint move straight) and with it (the moves to the bin go around it,
checked against the post, the fixtures and the held cube), both with the overhead depth
camera and the occupancy map (`make demo`) and both with the perfect camera. Each row
prints the real-time factor, the sim time, and the steps in which the arm touched the post.

Run: .venv/bin/python bench/demo_obstacle.py   (in `make bench`)
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from skillbus import paths
from skillbus.netns import Sandbox, last_json
from skillbus.sim import scene as scenes
from skillbus.system import programs, start


def without_post(folder: Path) -> Path:
    """The demo scene less its obstacles, with its world model file beside it."""
    doc = json.loads(paths.demo_scene().read_text())
    doc.pop("obstacles", None)
    path = scenes.save(doc, folder / "no_post.scene.json", paths.demo_scene())
    (folder / "no_post.ttl").write_text(scenes.to_turtle(scenes.load(path)))
    return path


def demo(run: Path, scene: Path, perception: bool) -> dict:
    run.mkdir(parents=True)
    with Sandbox(log_dir=run / "logs") as box:
        procs = start(box, programs(run, scene=scene, perception=perception), run)
        box.wait(procs["sim"], 900)
        box.wait(procs["skill_mgr"], 60)
        sim = last_json(procs["sim"].stdout())
        sim["task"] = last_json(procs["skill_mgr"].stdout())["tasks"].get("1", "?")
    return sim


def main() -> int:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        bare = without_post(Path(tmp))
        for perception in (True, False):
            for label, scene in (("before: no post, straight moves", bare), ("after: the post, moves around it", paths.demo_scene())):
                d = demo(Path(tmp) / f"{'p' if perception else 'g'}-{len(rows)}", scene, perception)
                row = {"perception": perception, "scene": label, "task": d["task"], "rtf": d["real_time_factor"],
                       "sim_time_s": d["sim_time_s"], "wall_time_s": d["wall_time_s"],
                       "post_contact_steps": d.get("obstacle_contact_steps", {}).get("post")}
                rows.append(row)
                print(f"{'camera' if perception else 'perfect camera'}, {label}: {d['task']}; "
                      f"{d['sim_time_s']:.2f} s sim in {d['wall_time_s']:.2f} s: {d['real_time_factor']:.2f}x real time; "
                      f"arm on the post: {row['post_contact_steps']} steps", flush=True)
            before, after = rows[-2], rows[-1]
            print(f"  ratio after/before ({'camera' if perception else 'perfect camera'}): "
                  f"{after['rtf'] / before['rtf']:.2f}x real-time factor, {after['sim_time_s'] / before['sim_time_s']:.2f}x sim time")
    print(json.dumps({"demo_obstacle": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
