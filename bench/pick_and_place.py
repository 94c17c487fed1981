"""Benchmark of the whole pick-and-place demo (ClearTable in lockstep, every process real)
beside the physics server alone running the same scene and the same motions in the same
run, and where a frame's wall time goes.

The physics server of the demo records every command it applied, with its frame
(--record-script); the physics alone then replays exactly those (--script), which gives
the same physics bit for bit (the two state digests are compared), without any
participant, transport or skill. Both at the demo's 20 ms frames and at 10 ms frames.

Targets (issue "Performance"): at 20 ms frames the demo keeps at least 90 % of the
physics-alone speed and runs at least 10x real time on this 2-core machine.

At 20 ms frames the pair (demo, then the physics alone) is run five times and the median
ratio is the figure: one pair moved from 78 to 102 % within an hour on this machine, and
three pairs' median by 6 points between two runs of the bench.

Run: .venv/bin/python bench/pick_and_place.py   (in `make bench`)
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

from skillbus import cpu_layout, paths
from skillbus.netns import Sandbox, last_json
from skillbus.system import programs, start


REPEATS = 5  # paired runs at 20 ms frames


def demo(box: Sandbox, run: Path, frame_ms: float) -> dict:
    script = run / "applied.json"
    # Placed as `skillbus demo` places them: the physics server on a core of its own.
    layout = cpu_layout.place(programs(run, frame_ms=frame_ms, extra_sim=("--record-script", str(script))))
    procs = start(box, layout.programs, run)
    box.wait(procs["sim"], 900)
    box.wait(procs["skill_mgr"], 60)
    sim = last_json(procs["sim"].stdout())
    sim["task"] = last_json(procs["skill_mgr"].stdout())["tasks"].get("1", "?")
    sim["script"] = str(script)
    sim["cores"] = layout.note
    sim["physics_prefix"] = next(p.argv[:p.argv.index(str(paths.binary("sim_server")))] for p in layout.programs
                                 if p.name == "sim")
    sim["physics_options"] = layout.physics_options
    return sim


def alone(box: Sandbox, script: str, frames: int, frame_ms: float, prefix: list[str], options: list[str]) -> dict:
    """The physics server alone, placed as the demo's was: on its core (`prefix`: its
    taskset), with the placement's options (`options`: idle cores polling when the demo's
    had it, so that both run on the same machine settings)."""
    p = box.start("alone", [*prefix, str(paths.binary("sim_server")), "--scene", str(paths.demo_scene()), "--frame-ms",
                            str(frame_ms), "--script", script, "--frames", str(frames), *options])
    box.wait(p, 900)
    return last_json(p.stdout())


def one_run(tmp: Path, frame_ms: float, n: int) -> dict:
    """The demo, then the physics alone on its recorded commands: one paired run."""
    run = Path(tmp) / f"f{int(frame_ms)}-{n}"
    run.mkdir()
    with Sandbox(log_dir=run / "logs") as box:
        d = demo(box, run, frame_ms)
        a = alone(box, d["script"], d["frames"], frame_ms, d["physics_prefix"], d["physics_options"])
    return {"frame_ms": frame_ms, "task": d["task"], "sim_time_s": d["sim_time_s"], "demo_wall_s": d["wall_time_s"],
            "demo_rtf": d["real_time_factor"], "alone_wall_s": a["wall_time_s"], "alone_rtf": a["real_time_factor"],
            "ratio": d["real_time_factor"] / a["real_time_factor"],
            "same_physics": d["state_digest"] == a["state_digest"],
            "frame_breakdown_ms": d.get("frame_ms", {}), "frames_ended_by": d.get("frames_ended_by", {}),
            "cores": d["cores"]}


def main() -> int:
    # The ratio of two runs of a second and a half each moves by a few per cent with the
    # machine (the physics alone alone has ranged 26.4x-28.6x within an hour): at 20 ms
    # frames, where the target is, the figure is the median of REPEATS paired runs.
    repeats = {20.0: REPEATS, 10.0: 1}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for frame_ms in (20.0, 10.0):
            runs = [one_run(Path(tmp), frame_ms, n) for n in range(repeats[frame_ms])]
            for r in runs:
                fm, ended = r["frame_breakdown_ms"], r["frames_ended_by"]
                held = ", ".join(f"{k[5:]} {v:.3f} (last in {100 * ended.get(k[5:], 0):.0f} %)"
                                 for k, v in sorted(fm.items()) if k.startswith("held_"))
                print(f"frames of {frame_ms:.0f} ms: ClearTable ({r['task']}) {r['sim_time_s']:.2f} s of sim time in "
                      f"{r['demo_wall_s']:.2f} s: {r['demo_rtf']:.2f}x real time; the physics alone, same "
                      f"motions: {r['alone_wall_s']:.2f} s, {r['alone_rtf']:.2f}x; the demo keeps "
                      f"{100 * r['ratio']:.1f} % of it (same physics bit for bit: {r['same_physics']}; {r['cores']})")
                print(f"    per frame (ms): state {fm.get('state', 0):.2f}, physics {fm.get('physics', 0):.2f}, "
                      f"wait for acks {fm.get('ack_wait', 0):.2f} (past the physics "
                      f"{fm.get('ack_wait', 0) - fm.get('physics', 0):.2f}), total {fm.get('total', 0):.2f}; "
                      f"acks past the physics by participant: {held}", flush=True)
            row = dict(sorted(runs, key=lambda r: r["ratio"])[len(runs) // 2])  # the median run
            row["runs"] = [{k: r[k] for k in ("demo_rtf", "alone_rtf", "ratio", "same_physics")} for r in runs]
            row["demo_rtf"] = sorted(r["demo_rtf"] for r in runs)[len(runs) // 2]  # (its own median)
            row["same_physics"] = all(r["same_physics"] for r in runs)
            rows.append(row)
            if len(runs) > 1:
                kept = ", ".join(f"{100 * r['ratio']:.1f}" for r in runs)
                demos = ", ".join(f"{r['demo_rtf']:.1f}" for r in runs)
                alones = ", ".join(f"{r['alone_rtf']:.1f}" for r in runs)
                print(f"frames of {frame_ms:.0f} ms, {len(runs)} paired runs: the demo keeps {kept} % (median "
                      f"{100 * row['ratio']:.1f} %); the demo {demos}x, the physics alone {alones}x")
    r20 = next(r for r in rows if r["frame_ms"] == 20.0)
    print(f"target: at 20 ms frames the demo keeps at least 90 % of the physics alone: "
          f"{'met' if r20['ratio'] >= 0.9 else 'NOT met'} ({100 * r20['ratio']:.1f} %, the median of "
          f"{len(r20['runs'])} paired runs)")
    print(f"target: at 20 ms frames the demo runs at least 10x real time: "
          f"{'met' if r20['demo_rtf'] >= 10 else 'NOT met'} ({r20['demo_rtf']:.1f}x, the median)")
    if not all(r["same_physics"] for r in rows):
        print("the demo's physics and the physics alone differed in a run: the ratio compares different work")
    print(json.dumps({"pick_and_place": rows}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
