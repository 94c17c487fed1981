"""skillbus.skill.warm_up: a library's slow start-up work, waited for with a bound."""

import logging
import threading

from skillbus.skill import warm_up


def test_wait_returns_once_the_work_ended_and_names_what_is_still_running():
    release = threading.Event()
    done = []
    warm_up.in_background(lambda: done.append(1), "quick")
    warm_up.in_background(lambda: release.wait(10), "held")
    assert warm_up.wait(0.3) == ["held"]
    assert done == [1]
    release.set()
    assert warm_up.wait(5) == []
    assert "held" not in warm_up.running()


def test_a_failing_warm_up_is_logged_by_name_and_not_raised(caplog):
    def broken():
        raise ImportError("no planner here")
    with caplog.at_level(logging.WARNING, logger="skillbus.skill"):
        warm_up.in_background(broken, "planner-import")
        assert warm_up.wait(5) == []
    assert "warm-up planner-import failed (ImportError: no planner here)" in caplog.text
