"""One way to wait: poll a condition until it holds or a deadline passes.

Every wait in skillbus and in its tests has a timeout, and a wait that runs out says what
it waited for, and, given a ``diagnostic``, what the awaited thing had to say (a
process's last stderr, a device's state):

>>> import itertools
>>> polls = itertools.count(1)
>>> wait_until(lambda: next(polls) >= 3, 5.0, "the third poll", interval=0.001)
True
>>> wait_until(lambda: False, 0.02, "a miracle", interval=0.005, diagnostic=lambda: "none came")
Traceback (most recent call last):
    ...
skillbus.waiting.WaitTimeout: a miracle: not within 0.02 s
none came

:func:`poll_until` is the same loop for a wait whose end is not an error (try for a while,
then do something else): it returns the predicate's last value instead of raising.

>>> poll_until(lambda: 0, 0.01, interval=0.005)
0

Between polls ``step(seconds)`` runs, by default ``time.sleep``; to dispatch a bus while
waiting, pass ``step=bus.handle`` (it returns as soon as a message was handled, so the
predicate sees it at once). A predicate that knows the wait is hopeless (the process it
watches has exited) raises, and that exception ends the wait at once; exceptions listed
in ``retry_on`` count as "not yet" instead (a server that does not answer yet), and the
last of them is named when the time runs out.

Not for the protocol loops with a deadline of their own (RPC resends, lockstep frame
messages, the CAN link's frames): those are waits inside one exchange, measured and
tuned, not polling.
"""

from __future__ import annotations

import re
import time
from typing import Callable, TypeVar

T = TypeVar("T")

__all__ = ["WaitTimeout", "poll_until", "wait_until", "wait_for_text"]


class WaitTimeout(TimeoutError):
    """A wait ran out. ``what`` is what was awaited, ``timeout`` how long, ``detail`` the
    diagnostic's output and the last retried error (may be empty)."""

    def __init__(self, what: str, timeout: float, detail: str = "") -> None:
        self.what, self.timeout, self.detail = what, timeout, detail
        super().__init__(f"{what}: not within {timeout:g} s" + (f"\n{detail}" if detail else ""))

    def __str__(self) -> str:  # (OSError's own would print a tuple)
        return self.args[0]


def _loop(predicate: Callable[[], T], timeout: float, interval: float, step: Callable[[float], object] | None,
          retry_on: tuple[type[BaseException], ...]) -> tuple[T | None, bool, BaseException | None]:
    """Polls; returns (last value, whether it held, the last retried exception)."""
    deadline = time.monotonic() + timeout
    sleep = step or time.sleep
    error: BaseException | None = None
    while True:
        try:
            value = predicate()
        except retry_on as e:
            value, error = None, e
        else:
            if value:
                return value, True, error
        left = deadline - time.monotonic()
        if left <= 0:
            return value, False, error
        sleep(min(interval, left))


def wait_until(predicate: Callable[[], T], timeout: float, what: str, *, interval: float = 0.05,
               diagnostic: Callable[[], str] | None = None, step: Callable[[float], object] | None = None,
               retry_on: tuple[type[BaseException], ...] = ()) -> T:
    """Calls ``predicate()`` until it returns something true, and returns that value; the
    predicate is called at least once, and once more at the deadline. Raises
    :class:`WaitTimeout` ("<what>: not within <timeout> s", then the last retried error
    and the diagnostic's output) when ``timeout`` seconds pass first."""
    value, held, error = _loop(predicate, timeout, interval, step, retry_on)
    if held:
        return value  # type: ignore[return-value]
    detail = []
    if error is not None:
        detail.append(f"last error: {type(error).__name__}: {error}")
    if diagnostic is not None:
        try:
            detail.append(str(diagnostic()))
        except Exception as e:  # a broken diagnostic must not hide the timeout
            detail.append(f"(the diagnostic failed: {e!r})")
    raise WaitTimeout(what, timeout, "\n".join(d for d in detail if d)) from error


def poll_until(predicate: Callable[[], T], timeout: float, *, interval: float = 0.05,
               step: Callable[[float], object] | None = None,
               retry_on: tuple[type[BaseException], ...] = ()) -> T | None:
    """The loop of :func:`wait_until` for a wait whose end is not an error: returns the
    first true value of ``predicate()``, or its last value when ``timeout`` has passed
    (None if the last call raised one of ``retry_on``)."""
    value, _, _ = _loop(predicate, timeout, interval, step, retry_on)
    return value


def wait_for_text(read: Callable[[], str], pattern: str | re.Pattern[str], timeout: float, what: str, *,
                  ended: Callable[[], int | None] | None = None, interval: float = 0.05,
                  diagnostic: Callable[[], str] | None = None) -> re.Match[str]:
    """Waits until the text ``read()`` returns (a log, a process's output) contains
    ``pattern`` (a string: literally; a compiled expression: searched) and returns the
    match. With ``ended`` (a process's exit code, None while it runs), a process that
    has ended without writing it ends the wait at once: RuntimeError naming the code.

    >>> wait_for_text(lambda: "joined; ready", "ready", 1.0, "readiness").group(0)
    'ready'
    """
    rx = pattern if isinstance(pattern, re.Pattern) else re.compile(re.escape(pattern))

    def found() -> re.Match[str] | None:
        code = ended() if ended is not None else None
        m = rx.search(read())  # (read after the exit code: what it wrote before ending counts)
        if m is None and code is not None:
            detail = diagnostic() if diagnostic is not None else ""
            raise RuntimeError(f"{what}: it ended (exit code {code}) without it" + (f"\n{detail}" if detail else ""))
        return m

    return wait_until(found, timeout, what, interval=interval, diagnostic=diagnostic)
