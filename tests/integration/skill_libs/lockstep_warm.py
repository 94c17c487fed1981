"""Test library with a slow warm-up: Warmed fails when it runs before the warm-up ended."""

import time

from skillbus.skill import PrimitiveBase, SkillDescription, warm_up

WARM_UP_S = 3.0
ended = False


def _slow_warm_up() -> None:
    global ended
    time.sleep(WARM_UP_S)
    ended = True


warm_up.in_background(_slow_warm_up, "slow-warm-up")


class Warmed(SkillDescription):
    pass


class warmed(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Warmed(), "warmed")

    def execute(self):
        return self.success("the warm-up had ended") if ended else self.fail("the warm-up was still running", -1)
