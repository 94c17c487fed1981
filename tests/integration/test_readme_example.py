"""The skill example in README.md works as written (the docs cannot rot silently)."""

import re
import sys
from pathlib import Path

from test_skills import cli, start_system

README = Path(__file__).resolve().parents[2] / "README.md"


def test_readme_skill_example_runs(sandbox, tmp_path):
    code = re.search(r"```python\n(from skillbus\.skill import .*?)```", README.read_text(), re.S).group(1)
    (tmp_path / "my_skills.py").write_text(code)
    import test_skills
    old = test_skills.LIBS
    test_skills.LIBS = tmp_path  # the example's module is the library
    try:
        start_system(sandbox, "my_skills")
        rc, out, err = cli(sandbox, "run", "Twice", "--watch", "--verbose", "--timeout", "30")
    finally:
        test_skills.LIBS = old
    assert rc == 0, out + err
    assert "Total=3" in out and "task 1: Success" in out
