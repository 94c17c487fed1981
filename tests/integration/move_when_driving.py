"""Test helper for test_task_plan.py: waits until the robot is between shelves (Drive has
taken it away from where it was: no skiros:at relation), then moves a product to another
shelf in the world model, as a person would while the robot is on its way. Prints one JSON
line: {"moved": true, "robot_was_at": ...}.

    move_when_driving.py ROBOT PRODUCT NEW_SHELF TIMEOUT_S
"""

import json
import sys
import time

from skillbus.bus import open_bus
from skillbus.world.client import WorldModelInterface
from skillbus.world.poses import reparent


def main() -> int:
    robot, product, shelf, timeout = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
    bus = open_bus(None)
    wmi = WorldModelInterface(bus, "mover")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if not wmi.get_relations(robot, "skiros:at", ""):
            reparent(wmi, product, shelf)
            print(json.dumps({"moved": True, "at": time.monotonic()}))
            return 0
        bus.handle(0.01)  # (the replica follows the world model's changes as they are dispatched)
    print(json.dumps({"moved": False}))
    return 1


if __name__ == "__main__":
    sys.exit(main())
