"""TaskPlan: goals in, skills out (docs/planning.md).

`TaskPlan` takes SkiROS2's Goal string ("(skiros:contain skiros:Bin-5 skiros:Cube-2),
(...)"). Its tree is one `PlanSteps`, retried `Replans` times (RetryOnFail): each start of
PlanSteps plans from the world model as it is then (skillbus.planning: the skills the
skill manager has registered, from every skill process, Fast Downward) and runs the plan as a SerialStar
of the planned skills, their element parameters bound. A step that fails (its
pre-condition false because the world changed, a fault) fails PlanSteps, which plans
again from the new world; after the last replan the failure names the step. A goal that
cannot be reached, or is malformed, fails PlanSteps at its start naming why.
"""

from __future__ import annotations

from skillbus.skill import ParamTypes, RetryOnFail, SerialStar, SkillBase, SkillDescription, warm_up

GOAL_HELP = ("facts to reach, separated by commas: (skiros:contain skiros:Bin-5 skiros:Cube-2), "
             "(not (skiros:contain skiros:Gripper-7 skiros:Cube-4))")


def _plan_params(d: SkillDescription) -> None:
    d.addParam("Goal", "", ParamTypes.Required, description=GOAL_HELP)
    d.addParam("Optimal", False, ParamTypes.Optional,
               description="the fewest skills (Fast Downward's A* with LM-cut) instead of the first plan found")
    d.addParam("TimeLimit", 10.0, ParamTypes.Optional, description="seconds of planning at most, per plan")


class TaskPlan(SkillDescription):
    def createDescription(self):
        _plan_params(self)
        self.addParam("Replans", 1, ParamTypes.Optional,
                      description="when a step fails, plan again from the world as it is, this many times")


class PlanSteps(SkillDescription):
    def createDescription(self):
        _plan_params(self)


class task_plan(SkillBase):
    available_for_planning = False

    def createDescription(self):
        self.setDescription(TaskPlan(), "task_plan")

    def expand(self, skill):
        replans = int(self.params["Replans"].value)
        if replans < 0:
            raise ValueError(f"Replans must be >= 0, not {replans}")
        attempt = self.skill("PlanSteps", "plan_steps")
        skill.setProcessor(SerialStar())
        skill(self.skill(RetryOnFail(replans))(attempt) if replans else attempt)


class plan_steps(SkillBase):
    available_for_planning = False

    def createDescription(self):
        self.setDescription(PlanSteps(), "plan_steps")

    def expand(self, skill):
        from skillbus.planning.model import skill_from_msg, world_from_client
        from skillbus.planning.solve import make_plan
        if self.wmi is None:
            raise RuntimeError("TaskPlan plans from the world model: run the skill process with --world-model")
        registered = getattr(self, "registered_skills", None)  # set by the skill process
        skills = [skill_from_msg(m) for m in (registered() if registered else [])]
        plan = make_plan(skills, world_from_client(self.wmi), str(self.params["Goal"].value),
                         optimal=bool(self.params["Optimal"].value), time_limit=float(self.params["TimeLimit"].value))
        skill.setProcessor(SerialStar())
        skill(*[self.skill(s.skill.type, s.skill.label, specify={k: self.wmi.get_element(v) for k, v in s.params.items()})
                for s in plan.steps])


def _warm_up() -> None:
    """Imports the planner (Unified Planning takes about 2.5 s to import) when this library
    loads, beside the process's start, so that its first plan does not pay for the import
    (under lockstep the process joins once it is done: skillbus.skill.warm_up)."""
    from skillbus.planning import solve
    solve._engine()


warm_up.in_background(_warm_up, "planner-import")
