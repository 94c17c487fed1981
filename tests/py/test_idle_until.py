"""PrimitiveBase.idle_until: a primitive's word that its execute() would change nothing
until a sim time, carried to the manager in its tick reply (skill_tick_reply_t's
idle_until_ns). The skill process runs in-process on a memq:// bus; the manager's side
(skipping the ticks) is tests/integration/test_idle_ticks.py."""

from __future__ import annotations

import math

import pytest

from skillbus.msgs import skill_state_t, skill_tick_t
from skillbus.skill import ParamTypes, PrimitiveBase, SkillDescription
from skillbus import tick_context
from tick_messages import in_process, on_the_wire, tick_msg


class Wait(SkillDescription):
    def createDescription(self):
        self.addParam("Until", 1.0, ParamTypes.Required)   # s: idle until then, succeed after
        self.addParam("Idle", True, ParamTypes.Optional)   # False: step without a word


class wait_for(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Wait(), self.__class__.__name__)

    def execute(self):
        until = self.params["Until"].value
        if tick_context.now_s() >= until:
            return self.success("waited")
        if self.params["Idle"].value:
            self.idle_until(until)
        return self.step("waiting")


class idles_then_fails(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Wait(), self.__class__.__name__)

    def execute(self):
        self.idle_until(5.0)  # (a word that does not hold for an end)
        return self.fail("gave up", 3)


def tick(label: str, action: int, sim_s: float, **values) -> skill_tick_t:
    return tick_msg(label, action, frame=int(sim_s * 50), sim_time_ns=int(sim_s * 1e9), **values)


@pytest.fixture
def process():
    return in_process(__name__)



def test_a_running_skill_that_idles_says_until_when_in_its_reply(process):
    r = on_the_wire(process.on_tick(tick("wait_for", skill_tick_t.START, 0.2, Until=1.5)))
    assert (r.state, r.message, r.idle_until_ns) == (skill_state_t.RUNNING, "waiting", 1_500_000_000)


def test_an_execute_that_does_not_idle_again_clears_the_word(process):
    process.on_tick(tick("wait_for", skill_tick_t.START, 0.2, Until=1.5))
    r = on_the_wire(process.on_tick(tick("wait_for", skill_tick_t.EXECUTE, 0.4, Until=1.5, Idle=False)))
    assert (r.message, r.idle_until_ns) == ("waiting", 0)
    r = on_the_wire(process.on_tick(tick("wait_for", skill_tick_t.EXECUTE, 1.6, Until=1.5)))
    assert (r.message, r.idle_until_ns) == ("waited", 0)


def test_a_skill_that_ends_sends_no_idle_time(process):
    r = on_the_wire(process.on_tick(tick("idles_then_fails", skill_tick_t.START, 0.0)))
    assert (r.message, r.code, r.idle_until_ns) == ("gave up", -3, 0)


@pytest.mark.parametrize("bad", [-0.5, math.nan, math.inf, 1e10, "soon", None])
def test_a_time_that_is_no_sim_time_is_refused_naming_the_call(bad):
    s = wait_for()
    with pytest.raises(ValueError) as e:
        s.idle_until(bad)
    assert str(e.value).startswith(f"idle_until({bad!r}): a sim time in seconds"), e.value


def test_a_skill_whose_idle_time_is_refused_fails_its_tick_with_the_reason(process):
    class Bad(PrimitiveBase):
        def createDescription(self):
            self.setDescription(Wait(), "bad_idle")

        def execute(self):
            self.idle_until(-1)
            return self.step("never")
    process.classes["bad_idle"] = Bad
    r = process.on_tick(tick("bad_idle", skill_tick_t.START, 0.0))
    assert r.state == skill_state_t.FAILURE and "idle_until(-1)" in r.message and r.idle_until_ns == 0
