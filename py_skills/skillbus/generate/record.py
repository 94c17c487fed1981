"""An episode's rows from its LCM log (every message of a lockstep run is stamped with its
frame, so the rows come from the frames, never from arrival times or the wall clock).

A row every ``stride`` frames (the config's fps), from the physics server's state of that
frame (SB_SIM_STATE) and the articulated objects' reading (SB_ROBOT_ARTICULATION):

- ``observation.state``: the arm's joint positions, then the gripper's width (m);
- ``observation.velocity``: the arm's joint velocities;
- ``observation.tool_pose``: the tool centre point, x y z qx qy qz qw (world);
- ``observation.object_poses``: each object's pose, in scene order, 7 numbers each;
- ``observation.articulation``: each articulated joint's position, in report order;
- ``action``: what the robot was commanded: the arm's joint positions at the next row
  (the trajectory's effect over one row, as scripted demonstrations record it) and the
  gripper's commanded width.

The skill segments (which manipulation skill ran from which frame to which, and how it
ended) come from the skill manager's progress (SB_SKILL_PROGRESS). A log that misses a
frame's state is refused (RecordError): an episode with a hole is never written.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any


class RecordError(RuntimeError):
    pass


@dataclass
class Episode:
    rows: list[dict[str, Any]]
    names: dict[str, list[str]]          # per feature, the names of its values
    segments: list[dict[str, Any]] = field(default_factory=list)
    frames: int = 0
    shapes: dict[str, list[int]] = field(default_factory=dict)  # image features: [height, width]




def read(log: Path, stride: int, frame_ms: float) -> Episode:
    import lcm

    from skillbus.auth import strip
    from skillbus.msgs import (articulation_state_t, camera_cloud_t, decode, sim_state_t, skill_progress_t,
                               skill_state_t)
    from skillbus.perception.cloud import CloudAssembler, CloudError
    ended = {skill_state_t.SUCCESS: "Success", skill_state_t.FAILURE: "Failure"}
    states: dict[int, Any] = {}
    arts: dict[int, Any] = {}
    nodes: dict[int, dict[str, Any]] = {}  # node id -> segment
    ticks: dict[int, list[int]] = {}  # task -> the ticks its progress was published at
    assembler = CloudAssembler(keep=64)
    depth: dict[str, list[tuple[int, Any]]] = {}  # camera -> (frame, depth image) per whole capture
    captures: dict[str, list[int]] = {}  # camera -> capture numbers seen (parts of any)
    try:
        events = list(lcm.EventLog(str(log), "r"))
    except (OSError, IOError, ValueError) as e:
        raise RecordError(f"{log}: not a readable LCM log: {e}") from None
    for ev in events:
        ch = ev.channel
        data = strip(ev.data)  # (the bus's signature, if the run signed its messages)
        if ch == "SB_SIM_STATE":
            s = decode(sim_state_t, data)
            if s is not None:
                states.setdefault(s.header.frame, s)
        elif ch == "SB_CAMERA_CLOUD":
            m = decode(camera_cloud_t, data)
            if m is None or m.error or m.request_id:
                continue  # (a request's answer: not the camera's own rate)
            captures.setdefault(m.camera, []).append(m.capture)
            try:
                c = assembler.add(m, frame=m.header.frame)
            except CloudError as e:
                raise RecordError(f"{log}: camera {m.camera}: {e}") from None
            if c is not None:
                import numpy as np
                z = np.nan_to_num(c.points[:, :, 2], nan=0.0).astype(np.float32)  # m along the view; 0: no return
                depth.setdefault(c.camera, []).append((c.frame, z))
        elif ch == "SB_ROBOT_ARTICULATION":
            a = decode(articulation_state_t, data)
            if a is not None:
                arts.setdefault(a.header.frame, a)
        elif ch == "SB_SKILL_PROGRESS":
            p = decode(skill_progress_t, data)
            if p is None:
                continue
            ticks.setdefault(p.task, []).append(p.tick)
            for n in p.nodes:
                if not n.type.startswith("Manip") or n.type == "ManipTask":
                    continue
                seg = nodes.setdefault(n.id, {"skill": n.type, "label": n.label, "start_frame": None,
                                              "end_frame": None, "state": "Idle", "message": ""})
                if n.state == skill_state_t.RUNNING and seg["start_frame"] is None:
                    seg["start_frame"] = p.header.frame
                if n.state in ended:
                    if seg["end_frame"] is None:
                        seg["end_frame"] = p.header.frame
                    seg["state"], seg["message"] = ended[n.state], n.message
    for task, seen in ticks.items():  # the manager publishes a task's progress at every tick of it
        gaps = sorted(set(range(min(seen), max(seen) + 1)) - set(seen))
        if gaps:
            raise RecordError(f"{log}: the skill progress of task {task} at {len(gaps)} tick(s) is missing (first "
                              f"{gaps[0]}): the recording lost messages")
    for cam, seen in captures.items():
        whole = len(depth.get(cam, []))
        if whole != len(set(seen)):
            raise RecordError(f"{log}: camera {cam}: {len(set(seen)) - whole} capture(s) lost parts: the recording "
                              "lost messages")
    if not states:
        raise RecordError(f"{log}: no physics state in the log")
    first, last = min(states), max(states)
    missing = [f for f in range(first, last + 1) if f not in states]
    if missing:
        raise RecordError(f"{log}: the physics state of {len(missing)} frame(s) is missing (first {missing[0]}): "
                          "the recording lost messages")
    s0 = states[first]
    arm_idx = [i for i, n in enumerate(s0.joint_names) if "finger" not in n]
    arm_names = [s0.joint_names[i] for i in arm_idx]
    objects = [o.name for o in s0.objects]
    a0 = arts.get(first)
    joints = [f"{j.object}/{j.joint}" for j in a0.joints] if a0 is not None else []
    names = {
        "observation.state": arm_names + ["gripper_width"],
        "observation.velocity": arm_names,
        "observation.tool_pose": ["x", "y", "z", "qx", "qy", "qz", "qw"],
        "observation.object_poses": [f"{o}.{k}" for o in objects for k in ("x", "y", "z", "qx", "qy", "qz", "qw")],
        "observation.articulation": joints,
        "action": arm_names + ["gripper_width"],
    }
    shapes: dict[str, list[int]] = {}
    for cam, images in sorted(depth.items()):
        h, w = images[0][1].shape
        names[f"observation.depth.{cam}"] = ["height", "width"]
        shapes[f"observation.depth.{cam}"] = [h, w]
    picked = list(range(first, last + 1, stride))
    rows = []
    for k, f in enumerate(picked):
        s = states[f]
        nxt = states[picked[k + 1]] if k + 1 < len(picked) else s
        a = arts.get(f)
        if joints and (a is None or len(a.joints) != len(joints)):
            raise RecordError(f"{log}: the articulated objects' reading of frame {f} is missing")
        row_depth = {}
        for cam, images in sorted(depth.items()):
            seen = [img for fr, img in images if fr <= f]  # the latest whole capture by this frame
            img = seen[-1] if seen else images[0][1] * 0
            row_depth[f"observation.depth.{cam}"] = img.reshape(-1).tolist()
        rows.append({
            **row_depth,
            "frame": f,
            "timestamp": (f - first) * frame_ms / 1000.0,
            "observation.state": [s.position[i] for i in arm_idx] + [s.finger_width],
            "observation.velocity": [s.velocity[i] for i in arm_idx],
            "observation.tool_pose": list(s.tool_pose),
            "observation.object_poses": [v for o in s.objects for v in o.pose],
            "observation.articulation": [j.position for j in a.joints] if joints else [],
            "action": [nxt.position[i] for i in arm_idx] + [s.finger_width_target],
        })
    segments = sorted((v for v in nodes.values() if v["start_frame"] is not None), key=lambda v: v["start_frame"])
    return Episode(rows, names, segments, frames=last - first + 1, shapes=shapes)
