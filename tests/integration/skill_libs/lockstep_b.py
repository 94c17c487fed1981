"""Test library of process B: Other."""

import os
import sys

from skillbus.skill import ParamTypes, PrimitiveBase, SkillDescription


class Other(SkillDescription):
    def createDescription(self):
        self.addParam("Total", 0, ParamTypes.Optional)
        # (the kill test makes it tick for ever: killed "while it runs" must not race the
        # clock, which runs frames as fast as the participants ack them)
        self.addParam("N", int(os.environ.get("LOCKSTEP_B_OTHER_TICKS", "30")), ParamTypes.Optional)


class other(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Other(), "other")

    def onStart(self):
        print("other started", file=sys.stderr, flush=True)  # the kill test waits for this
        self.n = 0
        return True

    def execute(self):
        self.n += 1
        self.params["Total"].value = self.params["Total"].value + 10
        return self.step(f"{self.n}") if self.n < self.params["N"].value else self.success(f"other did {self.n}")
