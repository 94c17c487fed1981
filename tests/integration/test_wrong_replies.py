"""The skill manager checks what a skill process answers a tick before acting on it. A
parameter the skill does not have, a value of another type than declared, a state that
is no tick's answer, or a START/EXECUTE answered RUNNING that also says it ended the
instance fails the skill naming the process and what was wrong. Before, a foreign or
mistyped parameter went to the blackboard and on to the skill's siblings; a bad state
failed the skill without a reason; and an instance said ended was ticked on and never sent
its END. The real manager and a real skill process whose replies are altered
(lying_skill_process.py)."""

import sys
from pathlib import Path

import pytest

from test_skills import LIBS, cli, mgr_binary

HERE = Path(__file__).resolve().parent
BENCH = HERE.parent.parent / "bench"


def start_lying_system(sandbox, mode: str, library: str):
    sandbox.start("skill_mgr", [mgr_binary(), "--wall-clock"])
    proc = sandbox.start("liar", [sys.executable, str(HERE / "lying_skill_process.py"), mode, "skills-process",
                                  "--name", "liar", "--library", library],
                         env={"PYTHONPATH": f"{BENCH}:{LIBS}"})
    proc.wait_for("registered", 30)
    return proc


def run(sandbox, skill: str) -> str:
    rc, out, err = cli(sandbox, "run", skill, "--verbose", "--timeout", "20")
    assert rc == 1, out + err
    return out + err


def test_a_running_reply_that_says_it_ended_the_instance_fails_the_skill_naming_it(sandbox):
    start_lying_system(sandbox, "ended-running", "spin_skills")
    out = run(sandbox, "spin")
    assert "skill process liar answered the START of spin with RUNNING and said the same tick ended the " \
           "instance" in out, out
    assert "(its message: spinning)" in out, out


@pytest.mark.parametrize("state", [0, 1, 7, -3])
def test_a_state_that_is_no_ticks_answer_fails_the_skill_naming_it(sandbox, state):
    start_lying_system(sandbox, f"state={state}", "spin_skills")
    out = run(sandbox, "spin")
    assert f"skill process liar answered the START of spin with state {state}, which is not RUNNING, SUCCESS or " \
           "FAILURE" in out, out


def test_a_parameter_the_skill_does_not_have_never_reaches_its_siblings(sandbox):
    # produce has no Log; the Consume after it in Chain does, from the blackboard
    start_lying_system(sandbox, "param=produce:Log:str:planted", "flow_skills")
    out = run(sandbox, "Chain")
    assert "skill process liar answered the START of produce with a parameter Log that Produce does not have " \
           "(it has: Object, Ticks, Robot)" in out, out
    assert "planted" not in out.replace("Log:str:planted", ""), out
    assert "consumed" not in out, out  # nothing after it ran


def test_a_value_of_another_type_than_declared_never_reaches_its_siblings(sandbox):
    # produce's Object is a str; Consume gets it as its Item
    start_lying_system(sandbox, "param=produce:Object:int:42", "flow_skills")
    out = run(sandbox, "Chain")
    assert "skill process liar answered the START of produce with parameter Object as a int, where Produce " \
           "declares a str" in out, out
    assert "consumed" not in out, out
