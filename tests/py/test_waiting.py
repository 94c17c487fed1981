"""skillbus.waiting: the one polling loop every wait uses."""

import itertools
import subprocess
import sys
import time

import pytest

from skillbus.netns import Proc
from skillbus.waiting import WaitTimeout, poll_until, wait_for_text, wait_until


def test_returns_the_first_true_value_without_waiting_longer():
    polls = itertools.count(1)
    t0 = time.monotonic()
    assert wait_until(lambda: (n := next(polls)) >= 3 and n, 5.0, "the third poll", interval=0.01) == 3
    assert time.monotonic() - t0 < 1.0


def test_a_timeout_names_what_was_awaited_and_the_diagnostic():
    t0 = time.monotonic()
    with pytest.raises(WaitTimeout) as e:
        wait_until(lambda: False, 0.1, "the hub's socket", interval=0.01, diagnostic=lambda: "hub: no such file")
    assert 0.1 <= time.monotonic() - t0 < 1.0
    assert str(e.value) == "the hub's socket: not within 0.1 s\nhub: no such file"
    assert isinstance(e.value, TimeoutError) and e.value.what == "the hub's socket" and e.value.timeout == 0.1


def test_the_predicate_is_asked_at_least_once_and_at_the_deadline():
    calls = []
    assert wait_until(lambda: calls.append(1) or True, 0.0, "now") is True
    assert len(calls) == 1
    t0 = time.monotonic()
    # true only from 0.1 s on, asked at 0 and then every 0.3 s: the call at the deadline sees it
    assert wait_until(lambda: time.monotonic() - t0 >= 0.1, 0.15, "late", interval=0.3)


def test_retried_errors_count_as_not_yet_and_the_last_one_is_named():
    attempts = itertools.count(1)

    def connect():
        if next(attempts) < 3:
            raise ConnectionRefusedError("refused")
        return "connected"

    assert wait_until(connect, 5.0, "a connection", interval=0.001, retry_on=(ConnectionRefusedError,)) == "connected"
    with pytest.raises(WaitTimeout) as e:
        wait_until(lambda: 1 / 0, 0.05, "a division", interval=0.01, retry_on=(ZeroDivisionError,))
    assert "last error: ZeroDivisionError: division by zero" in str(e.value)
    assert isinstance(e.value.__cause__, ZeroDivisionError)


def test_any_other_error_ends_the_wait_at_once():
    t0 = time.monotonic()
    with pytest.raises(KeyError):
        wait_until(lambda: {}["gone"], 10.0, "a key", retry_on=(ValueError,))
    assert time.monotonic() - t0 < 1.0


def test_step_runs_between_polls_with_what_is_left():
    waited: list[float] = []
    poll_until(lambda: False, 0.05, interval=0.02, step=lambda s: (waited.append(s), time.sleep(s)))
    assert waited and all(0 < s <= 0.02 for s in waited)


def test_poll_until_returns_the_last_value_instead_of_raising():
    assert poll_until(lambda: [], 0.02, interval=0.005) == []
    assert poll_until(lambda: "yes", 0.02) == "yes"
    assert poll_until(lambda: 1 / 0, 0.02, interval=0.005, retry_on=(ZeroDivisionError,)) is None


def test_wait_for_text_fails_at_once_when_the_writer_has_ended():
    text = ["starting"]
    with pytest.raises(RuntimeError, match=r"readiness: it ended \(exit code 3\) without it\nits log"):
        wait_for_text(lambda: text[0], "ready", 10.0, "readiness", ended=lambda: 3, diagnostic=lambda: "its log")
    # what it wrote before it ended counts
    assert wait_for_text(lambda: "all ready", "ready", 1.0, "readiness", ended=lambda: 0).group(0) == "ready"


def test_a_process_is_waited_for_by_its_output(tmp_path):
    out, err = tmp_path / "p.out", tmp_path / "p.err"
    code = "import sys, time; time.sleep(0.2); print('joined (frame 1)', file=sys.stderr, flush=True); time.sleep(30)"
    with open(out, "wb") as fo, open(err, "wb") as fe:
        popen = subprocess.Popen([sys.executable, "-c", code], stdout=fo, stderr=fe)
    proc = Proc("p", popen, out, err)
    try:
        assert proc.wait_for("joined (frame", 10).group(0) == "joined (frame"  # literally: no regex
        with pytest.raises(WaitTimeout, match=r"(?s)p writing 'never' to stderr: not within 0.1 s\nthe end of p's stderr:\njoined"):
            proc.wait_for("never", 0.1)
    finally:
        popen.kill()
        popen.wait(10)
    with pytest.raises(RuntimeError, match=r"ended \(exit code -9\)"):
        proc.wait_for("never", 10)
