"""SkiROS2's template skill library, run with only its import lines changed (the
acceptance check of "a SkiROS2 skill module runs with only its imports changed").

Upstream: RVMI/skiros2_template_lib (branch master), src/skiros2_template_lib/
template_primitives.py (MyPrimitive, my_primitive) and template_skills.py (MySkill,
my_skill); its package.xml names the licence "BSD". Their text is read from the upstream
repository when this library is imported (skiros2_port.py says from where) and is not
kept here: only the import lines are rewritten, to skillbus.skill.
"""

from skiros2_port import load_upstream

UPSTREAM = load_upstream(globals(), "RVMI+skiros2_template_lib",
                         ["src/skiros2_template_lib/template_primitives.py",
                          "src/skiros2_template_lib/template_skills.py"])
