"""No Python file of the project uses a name that is not defined (pyflakes): the benches
run only in `make bench`, a test process only in its test, and a name left behind by an
edit there fails nowhere else (bench/skill_ticks.py's (c) failed so, after an edit meant
for (b))."""

from __future__ import annotations

from pathlib import Path

from pyflakes import api, messages, reporter

ROOT = Path(__file__).resolve().parents[2]
FOLDERS = ("bench", "py_skills/skillbus", "tests", "deploy")
# What is a bug wherever it is; unused imports and the like are left to review.
BUGS = (messages.UndefinedName, messages.UndefinedLocal, messages.UndefinedExport)


class Collect(reporter.Reporter):
    def __init__(self) -> None:
        super().__init__(None, None)
        self.found: list[str] = []

    def flake(self, message) -> None:
        if isinstance(message, BUGS):
            self.found.append(str(message))

    def syntaxError(self, filename, msg, lineno, offset, text) -> None:  # noqa: N802 (pyflakes' name)
        self.found.append(f"{filename}:{lineno}: {msg}")

    def unexpectedError(self, filename, msg) -> None:  # noqa: N802
        self.found.append(f"{filename}: {msg}")


def test_no_python_file_uses_an_undefined_name():
    files = sorted(f for folder in FOLDERS for f in (ROOT / folder).rglob("*.py"))
    assert len(files) > 100
    out = Collect()
    for f in files:
        api.checkPath(str(f), out)
    assert out.found == []


def test_the_check_finds_an_undefined_name(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("def f():\n    return [*answering, 1]\n")
    out = Collect()
    api.checkPath(str(bad), out)
    assert len(out.found) == 1 and "answering" in out.found[0]
