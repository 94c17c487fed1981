"""Ctrl-C for the tests' processes, whatever started the test run.

Several tests send SIGINT to a process they started (a skill process, `skillbus generate`)
and check that it ends cleanly, or check the handler Python installs for it. A process
started with SIGINT ignored passes that on to every child it starts: a test run launched as
a background job of a non-interactive shell, or under `nohup`, made those tests fail for
the runner's sake, not the code's (seen: four failures in one such `make test`). The run
therefore takes SIGINT back as Python's default before any test starts; the children it
starts then get the default action again.
"""

from __future__ import annotations

import signal


def restore_ctrl_c() -> None:
    """SIGINT back to Python's default handler when this process was started with it ignored."""
    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
