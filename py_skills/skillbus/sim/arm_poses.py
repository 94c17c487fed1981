"""Joint positions for top-down tool poses of the demo arm (sim_server/models/arm6.urdf),
solved in closed form: the arm's yaw, a two-link shoulder-elbow solution in the arm's
vertical plane, and the wrist pitch that points the tool straight down.

Public API, for command scripts (skillbus.sim.scripts, ``skillbus sim-script``), the
benchmarks and the tests: ``top_down`` and the joint names ``ARM``. The skills use the
general IK of the motion service instead; this needs no server.

>>> q = top_down(0.5, 0.0, 0.5)
>>> [round(x, 4) for x in q]
[0.0, 0.6252, 1.465, 0.0, 1.0513, 0.0]
>>> round(q[1] + q[2] + q[4], 12) == round(math.pi, 12)  # shoulder, elbow, wrist: straight down
True
>>> top_down(2.0, 0.0, 0.5)
Traceback (most recent call last):
    ...
ValueError: (2.0, 0.0, 0.5) is out of reach
"""

from __future__ import annotations

import math

SHOULDER_Z = 0.5          # joint2 above the floor: pedestal 0.4 + link1 0.1
UPPER, FOREARM = 0.35, 0.34   # joint2->joint3, joint3->joint5 (0.30 + 0.04)
WRIST_TO_TCP = 0.115      # joint5->joint6 0.06 + tool offset 0.055
ARM = ["joint1", "joint2", "joint3", "joint4", "joint5", "joint6"]


def top_down(x: float, y: float, z: float, yaw: float = 0.0) -> list[float]:
    """Joints that put the tool centre point at (x, y, z), pointing down, fingers closing
    along the world axis at `yaw` from y."""
    j1 = math.atan2(y, x)
    r = math.hypot(x, y)
    h = z + WRIST_TO_TCP - SHOULDER_Z
    c3 = (r * r + h * h - UPPER ** 2 - FOREARM ** 2) / (2 * UPPER * FOREARM)
    if abs(c3) > 1:
        raise ValueError(f"({x}, {y}, {z}) is out of reach")
    q3 = math.acos(c3)
    q2 = math.atan2(r, h) - math.atan2(FOREARM * math.sin(q3), UPPER + FOREARM * math.cos(q3))
    q5 = math.pi - q2 - q3
    return [j1, q2, q3, 0.0, q5, j1 - yaw]
