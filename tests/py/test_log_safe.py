"""Logs take text from the wire: every record is one escaped, bounded line."""

import logging
import subprocess
import sys


def test_a_forged_newline_or_escape_cannot_make_log_lines():
    code = ("from skillbus.log import setup_logging; import logging; setup_logging();"
            "logging.getLogger('sim').warning('bad message: %s', 'x\\n[INFO] wm: all well\\x1b[2K' + 'y' * 5000)")
    err = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=30).stderr
    lines = err.splitlines()
    assert len(lines) == 1, err[:500]
    assert lines[0].startswith("[WARNING] sim: bad message: x\\x0a[INFO] wm: all well\\x1b[2K")
    assert lines[0].endswith("more characters)") and len(lines[0]) < 2100


def test_a_traceback_stays_readable():
    code = ("from skillbus.log import setup_logging; import logging; setup_logging()\n"
            "try:\n    1 / 0\nexcept ZeroDivisionError:\n    logging.getLogger('x').exception('failed')")
    err = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=30).stderr
    assert err.startswith("[ERROR] x: failed\nTraceback") and "ZeroDivisionError" in err
