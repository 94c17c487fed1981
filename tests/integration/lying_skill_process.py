"""A real skill process whose tick replies are made wrong on purpose, to test what the
skill manager does with them (test_wrong_replies.py).

    lying_skill_process.py MODE skills-process ARGS...

MODE, for every START and EXECUTE reply:
- `ended-running`: a reply RUNNING also says the tick ended the instance;
- `state=N`: the reply's state is N;
- `param=LABEL:KEY:TYPE:VALUE`: the replies of LABEL's ticks carry a parameter KEY of
  value type TYPE (str, int) with VALUE, besides the skill's own (replacing one of that key),
  with data_type "" (a reply that claims no type)."""

from __future__ import annotations

import sys

from skillbus.cli import main
from skillbus.msgs import skill_param_t, skill_state_t, skill_tick_t, skill_value_t
from skillbus.skill import process

MODE = sys.argv[1]
_honest_tick = process.SkillProcess._tick


def _extra_param(key: str, kind: str, text: str) -> skill_param_t:
    v = skill_value_t()
    if kind == "int":
        v.type, v.i = skill_value_t.INT, int(text)
    else:
        v.type, v.s = skill_value_t.STRING, text
    p = skill_param_t()
    p.key, p.data_type, p.param_type = key, "", skill_param_t.OPTIONAL
    p.values, p.num_values = [v], 1
    return p


def _lying_tick(self, t):
    r = _honest_tick(self, t)
    if t.action not in (skill_tick_t.START, skill_tick_t.EXECUTE):
        return r
    if MODE == "ended-running" and r.state == skill_state_t.RUNNING:
        r.ended = True
    elif MODE.startswith("state="):
        r.state = int(MODE.split("=", 1)[1])
    elif MODE.startswith("param="):
        label, key, kind, text = MODE.split("=", 1)[1].split(":", 3)
        if t.label == label:
            m = r.as_message()
            m.params = [p for p in m.params if p.key != key] + [_extra_param(key, kind, text)]
            m.num_params = len(m.params)
            return m
    return r


process.SkillProcess._tick = _lying_tick

if __name__ == "__main__":
    sys.exit(main(sys.argv[2:]))
