"""A manager's tick as the skill process receives it, for tests that drive a SkillProcess
in-process: skill_tick_t with one value per parameter (bool, int or float by its Python
type), through the wire and back."""

from __future__ import annotations

from skillbus.msgs import skill_param_t, skill_tick_t, skill_value_t


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
