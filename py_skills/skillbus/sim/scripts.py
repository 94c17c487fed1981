"""Command scripts for the physics server (the format of skillbus sim-script and of
sim_server --script): examples to start from, and the scripts the tests and benchmarks
play (grasp, lift and release; a sweep of every joint; grasp and carry).

Public API (not a test fixture: bench/sim_physics.py uses it as the tests do): ``arm``,
``gripper`` (one step each), ``grasp_lift_release``, ``sweep``, ``grasp_and_carry``,
``CUBE`` and ``HOME`` for the demo scene. A script is a dict; ``json.dump`` it for
``skillbus sim-script``:

>>> step = gripper(4.0, "close", 0.0)
>>> step["gripper"]["id"], step["gripper"]["width"], step["at_s"]
('close', 0.0, 4.0)
>>> [s["at_s"] for s in grasp_lift_release()["steps"]]
[0.0, 2.2, 4.0, 5.0, 7.5]
"""

from __future__ import annotations

from skillbus.sim.arm_poses import ARM, top_down

CUBE = (0.5, -0.1, 0.425)  # the green cube of the demo scene
HOME = [0.0, 0.2, 1.6, 0.0, 1.3416, 0.0]


def arm(at_s: float, cmd_id: str, points, joints=ARM) -> dict:
    return {"at_s": at_s, "arm": {"id": cmd_id, "joints": joints, "points": points}}


def gripper(at_s: float, cmd_id: str, width: float, speed: float = 0.1, force: float = 20.0) -> dict:
    return {"at_s": at_s, "gripper": {"id": cmd_id, "width": width, "speed": speed, "force_limit": force}}


def grasp_lift_release(record_every: int = 10) -> dict:
    """Above the green cube, down, close (20 N), lift 10 cm, hold, open (cube falls back)."""
    x, y, z = CUBE
    return {"record_every": record_every, "steps": [
        arm(0.0, "above", [[2.0, top_down(x, y, z + 0.105)]]),
        arm(2.2, "down", [[1.5, top_down(x, y, z + 0.005)]]),
        gripper(4.0, "close", 0.0),
        arm(5.0, "lift", [[1.5, top_down(x, y, z + 0.105)]]),
        gripper(7.5, "open", 0.08),
    ]}


def sweep(record_every: int = 1) -> dict:
    """A multi-point trajectory of every arm joint (no contact)."""
    pts = [[1.0, [0.4, 0.0, 1.2, 0.3, 1.2, -0.4]],
           [2.0, [0.8, -0.2, 0.9, 0.6, 1.0, 0.4]],
           [3.0, [0.2, 0.1, 1.4, -0.2, 1.5, 0.0]]]
    return {"record_every": record_every, "steps": [arm(0.5, "sweep", pts)]}


def grasp_and_carry(record_every: int = 1) -> dict:
    """Grasp the green cube, lift it, swing it 1.2 rad around the base in 1.5 s (the
    hardest motion of the demo for a grasp), bring it back and put it down. The swing goes
    clockwise, away from the bin: the other way the cube would strike the demo scene's post
    (which stands between the table and the bin), and the grasp figures would measure the blow."""
    x, y, z = CUBE
    up = top_down(x, y, z + 0.105)
    swung = list(up)
    swung[0] -= 1.2
    swung[5] -= 1.2  # the fingers keep their direction relative to the arm
    return {"record_every": record_every, "steps": [
        arm(0.0, "above", [[2.0, up]]),
        arm(2.2, "down", [[1.5, top_down(x, y, z + 0.005)]]),
        gripper(4.0, "close", 0.0),
        arm(5.0, "lift", [[1.0, up]]),
        arm(6.2, "swing", [[1.5, swung]]),
        arm(8.0, "back", [[1.5, up]]),
        arm(9.7, "put", [[1.0, top_down(x, y, z + 0.006)]]),
        gripper(11.0, "open", 0.08),
        arm(11.8, "leave", [[1.0, up]]),
    ]}
