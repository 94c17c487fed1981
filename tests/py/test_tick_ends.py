"""A primitive's end within the tick that finishes it: the skill process runs onEnd and
forgets the instance in the tick whose execute returned Success or Failure, and in every
PREEMPT, as SkiROS2 does within those calls, and says so in its reply
(skill_tick_reply_t.ended); the manager then sends no END. The skill process runs
in-process on a memq:// bus; the manager's side (no END sent, the same results) is
tests/integration/test_idle_ticks.py."""

from __future__ import annotations

import logging

import pytest

from skillbus.msgs import skill_state_t, skill_tick_reply_t, skill_tick_t
from skillbus.skill import ParamTypes, PrimitiveBase, SkillDescription
from tick_messages import in_process, on_the_wire, tick_msg

CALLS: list[str] = []


class Count(SkillDescription):
    def createDescription(self):
        self.addParam("Steps", 1, ParamTypes.Required)    # executes before it ends
        self.addParam("Fail", False, ParamTypes.Optional)  # end with a failure
        self.addParam("Note", "", ParamTypes.Optional)     # set by onEnd


class counter(PrimitiveBase):
    def createDescription(self):
        self.setDescription(Count(), self.__class__.__name__)

    def onStart(self):
        CALLS.append("onStart")
        self.n = 0
        return True

    def execute(self):
        CALLS.append("execute")
        self.n += 1
        if self.n < self.params["Steps"].value:
            return self.step(f"step {self.n}")
        if self.params["Fail"].value:
            return self.fail("counted wrong", 4)
        return self.success(f"counted {self.n}")

    def onPreempt(self):
        CALLS.append("onPreempt")
        return self.fail("stopped", 1)

    def onEnd(self):
        CALLS.append("onEnd")
        self.params["Note"].value = f"ended after {self.n}"
        self.message = "overwritten by onEnd"  # (the tick's result stays the execute's)
        return True


class raising_execute(counter):
    def execute(self):
        CALLS.append("execute")
        raise RuntimeError("a bug")


class raising_end(counter):
    def onEnd(self):
        CALLS.append("onEnd")
        raise RuntimeError("cleanup failed")


def tick(label: str, action: int, **values) -> skill_tick_t:
    return tick_msg(label, action, instance=7, **values)


@pytest.fixture
def process():
    CALLS.clear()
    return in_process(__name__)



def note(r: skill_tick_reply_t) -> str:
    return next(p.values[0].s for p in r.params if p.key == "Note")


def test_a_start_that_finishes_ends_the_instance_in_the_same_tick(process):
    r = on_the_wire(process.on_tick(tick("counter", skill_tick_t.START, Steps=1)))
    assert (r.state, r.message, r.ended) == (skill_state_t.SUCCESS, "counted 1", True)
    assert CALLS == ["onStart", "execute", "onEnd"]
    assert 7 not in process.instances
    assert note(r) == "ended after 1"  # the parameters as onEnd left them


def test_running_ticks_do_not_end_it_and_the_finishing_execute_does(process):
    r = on_the_wire(process.on_tick(tick("counter", skill_tick_t.START, Steps=3)))
    assert (r.state, r.ended) == (skill_state_t.RUNNING, False)
    r = on_the_wire(process.on_tick(tick("counter", skill_tick_t.EXECUTE, Steps=3)))
    assert (r.state, r.message, r.ended) == (skill_state_t.RUNNING, "step 2", False)
    assert 7 in process.instances and "onEnd" not in CALLS
    r = on_the_wire(process.on_tick(tick("counter", skill_tick_t.EXECUTE, Steps=3, Fail=True)))
    assert (r.state, r.message, r.code, r.ended) == (skill_state_t.FAILURE, "counted wrong", -4, True)
    assert CALLS.count("onEnd") == 1 and 7 not in process.instances


def test_a_preempt_runs_onpreempt_then_onend(process):
    process.on_tick(tick("counter", skill_tick_t.START, Steps=5))
    r = on_the_wire(process.on_tick(tick("counter", skill_tick_t.PREEMPT, Steps=5)))
    assert (r.state, r.message, r.ended) == (skill_state_t.FAILURE, "stopped", True)
    assert CALLS[-2:] == ["onPreempt", "onEnd"] and 7 not in process.instances


def test_an_end_sent_anyway_finds_no_instance_and_calls_nothing_twice(process):
    process.on_tick(tick("counter", skill_tick_t.START, Steps=1))
    r = on_the_wire(process.on_tick(tick("counter", skill_tick_t.END, Steps=1)))
    assert r.state == skill_state_t.FAILURE and "has no running instance 7" in r.message
    assert CALLS.count("onEnd") == 1


def test_an_end_still_ends_an_instance_that_is_running(process):
    """(A manager sends END where no reply said the instance ended: a tick the process
    refused, or one whose RPC failed with an error.)"""
    process.on_tick(tick("counter", skill_tick_t.START, Steps=5))
    r = on_the_wire(process.on_tick(tick("counter", skill_tick_t.END, Steps=5)))
    assert CALLS[-1] == "onEnd" and 7 not in process.instances
    assert r.ended is False  # (an END is the manager's own: it needs no word back)


def test_an_onend_that_raises_is_logged_and_the_result_stays(process, caplog):
    with caplog.at_level(logging.ERROR):
        r = on_the_wire(process.on_tick(tick("raising_end", skill_tick_t.START, Steps=1)))
    assert (r.state, r.message, r.ended) == (skill_state_t.SUCCESS, "counted 1", True)
    assert 7 not in process.instances
    assert "raising_end.onEnd failed" in caplog.text and "cleanup failed" in caplog.text


def test_a_tick_for_an_unknown_primitive_says_there_is_nothing_left_to_end(process):
    r = on_the_wire(process.on_tick(tick("nobody", skill_tick_t.START)))
    assert (r.state, r.ended) == (skill_state_t.FAILURE, True)


def test_an_execute_that_raises_still_ends_the_instance_with_its_onend(process):
    # Before, the instance was dropped without its onEnd: a skill's clean-up (a manipulation
    # skill stopping its arm) never ran after a bug in execute().
    r = on_the_wire(process.on_tick(tick("raising_execute", skill_tick_t.START, Steps=3)))
    assert (r.state, r.ended) == (skill_state_t.FAILURE, True)
    assert "raising_execute.execute() raised RuntimeError: a bug" in r.message
    assert CALLS == ["onStart", "execute", "onEnd"] and 7 not in process.instances
    process.on_tick(tick("counter", skill_tick_t.START, Steps=3))
    CALLS.clear()
    process.classes["counter"].execute = raising_execute.execute  # (this instance's next execute raises)
    try:
        r = on_the_wire(process.on_tick(tick("counter", skill_tick_t.EXECUTE, Steps=3)))
    finally:
        process.classes["counter"].execute = counter.__dict__["execute"]
    assert (r.state, r.ended) == (skill_state_t.FAILURE, True)
    assert CALLS == ["execute", "onEnd"] and 7 not in process.instances
