"""Judges a condition_skills description's pre-conditions in Python, with
Condition.evaluate(params, wmi), against the live world model: the Python side of
test_skill_conditions' comparison with the skill manager's own check.

    python condition_probe.py CheckRelation Subject=skiros:Table-1 Object=skiros:Cube-2

prints one JSON line: {condition label: holds as desired}. The description's parameters
are set as the manager sets them from ``-p KEY=ID``: to the world model's element.
"""

import json
import sys

import condition_skills

from skillbus.bus import open_bus
from skillbus.world import WorldModelInterface


def main(argv: list[str]) -> int:
    skill, pairs = argv[0], argv[1:]
    description = getattr(condition_skills, skill)()
    wmi = WorldModelInterface(open_bus(), "condition-probe")
    ph = description.params
    for pair in pairs:
        key, eid = pair.split("=", 1)
        ph.specify(key, wmi.get_element(eid))
    print(json.dumps({c.label: c.evaluate(ph, wmi) for c in description.preConditions}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
