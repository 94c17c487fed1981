"""SkiROS2's standard utility primitives, run with only their import lines changed
(``import rospy``, used for its clock only, becomes skillbus.skill.ros_clock).

Upstream: RVMI/skiros2_std_lib (branch master),
skiros2_std_skills/src/skiros2_std_skills/utility_primitives.py: Wait/wait,
WmSetRelation/wm_set_relation, WmSetProperties/wm_set_properties,
WmMoveObject/wm_move_object and wm_move_and_transform_object (that one needs SkiROS2's
spatial reasoner plug-in: it loads, but does not run here), Counter/counter; its
licence is the LGPL 3 (LICENSE.md). The text is read from the upstream repository when
this library is imported (skiros2_port.py says from where) and is not kept here.
"""

from skiros2_port import load_upstream

UPSTREAM = load_upstream(globals(), "RVMI+skiros2_std_lib",
                         ["skiros2_std_skills/src/skiros2_std_skills/utility_primitives.py"])
