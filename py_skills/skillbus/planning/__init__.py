"""Task planning from goals (docs/planning.md): the registered skills' pre- and
post-conditions and the world model become a planning problem (Unified Planning), solved
by Fast Downward; the plan is a sequence of skills with their parameters bound.

    model.py     the skills and the world as the planner sees them (from the bus or built in code)
    goals.py     SkiROS2's goal strings: "(skiros:contain skiros:Bin-5 skiros:Cube-2), ..."
    domain.py    skills -> actions, world -> objects and initial state (Unified Planning)
    solve.py     Fast Downward (satisficing or optimal, a time limit), why a goal cannot be reached
"""
