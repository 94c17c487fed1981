"""A command whose reader goes away (`skillbus ... | head`) ends quietly, exit 0."""

import subprocess
import sys


def test_output_into_a_closed_pipe_is_not_an_error():
    # `can-log` of a long candump log prints thousands of lines; `head -1` reads one.
    import tempfile
    from pathlib import Path
    with tempfile.TemporaryDirectory() as d:
        log = Path(d) / "long.log"
        log.write_text("".join(f"({i}.000000) vcan0 705#05\n" for i in range(20000)))
        p = subprocess.run(f"{sys.executable} -m skillbus.cli can-log {log} | head -1; echo \"rc=${{PIPESTATUS[0]}}\"",
                           shell=True, executable="/bin/bash", capture_output=True, text=True, timeout=60)
    lines = p.stdout.splitlines()
    assert len(lines) == 2 and lines[1] == "rc=0", p.stdout + p.stderr
    assert "Traceback" not in p.stderr and "Broken pipe" not in p.stderr, p.stderr
