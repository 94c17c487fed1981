"""For tests that drive a SkillProcess in-process: the process itself (on a memq:// bus),
a manager's tick as the process receives it (skill_tick_t with one value per parameter:
bool, int or float by its Python type, through the wire and back), and a reply as the
manager receives it."""

from __future__ import annotations

from skillbus.bus import open_bus
from skillbus.msgs import skill_param_t, skill_tick_reply_t, skill_tick_t, skill_value_t
from skillbus.skill.process import SkillProcess


def in_process(*libraries: str) -> SkillProcess:
    """A skill process named "t" on its own memq:// bus with `libraries` loaded, none failed."""
    proc = SkillProcess(open_bus("memq://"), "t", list(libraries))
    assert not proc.errors, proc.errors
    return proc


def on_the_wire(r) -> skill_tick_reply_t:
    """A reply as the manager decodes it."""
    return skill_tick_reply_t.decode(r.encode())


def tick_msg(label: str, action: int, instance: int = 1, frame: int = -1, sim_time_ns: int = 0,
             **values: bool | int | float) -> skill_tick_t:
    t = skill_tick_t()
    t.label, t.instance, t.action, t.frame, t.sim_time_ns = label, instance, action, frame, sim_time_ns
    for key, v in values.items():
        p = skill_param_t()
        p.key = key
        x = skill_value_t()
        if isinstance(v, bool):
            x.type, x.b = skill_value_t.BOOL, v
        elif isinstance(v, int):
            x.type, x.i = skill_value_t.INT, v
        else:
            x.type, x.f = skill_value_t.FLOAT, v
        p.values, p.num_values = [x], 1
        t.params.append(p)
    t.num_params = len(t.params)
    return skill_tick_t.decode(t.encode())
