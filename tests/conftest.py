"""Shared pytest fixtures. Multi-process tests get a Sandbox: a private network namespace
whose processes are always stopped, also when a test fails or times out."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from skillbus import paths
from skillbus import netns
from skillbus.netns import Sandbox, SandboxError

TESTS = Path(__file__).resolve().parent


@pytest.fixture
def sandbox(tmp_path):
    try:
        box = Sandbox(log_dir=tmp_path / "logs")
        box.__enter__()
    except SandboxError as e:
        pytest.skip(str(e))
    try:
        yield box
    finally:
        box.__exit__(None, None, None)


@pytest.fixture
def binary():
    return paths.binary


def python_tool(script: str, *args: str) -> list[str]:
    return [sys.executable, str(TESTS / "integration" / script), *args]


def last_json(text: str) -> dict:
    summary = netns.last_json(text)
    if summary is None:
        raise AssertionError(f"no JSON summary in output:\n{text[-2000:]}")
    return summary
