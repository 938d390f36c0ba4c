"""The tree passes the linter and the formatter configured in pyproject.toml (ruff)."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def _ruff():
    found = Path(sys.executable).with_name("ruff")
    if found.exists():
        return str(found)
    found = shutil.which("ruff")
    if found is None:
        pytest.fail("ruff is not installed; install the test extras (pip install -e '.[test]').")
    return found


@pytest.mark.parametrize("command", [["check", "--no-cache", "."], ["format", "--check", "--no-cache", "."]])
def test_ruff_finds_nothing(command):
    run = subprocess.run([_ruff(), *command], cwd=ROOT, capture_output=True, text=True)
    assert run.returncode == 0, f"ruff {' '.join(command)} found:\n{run.stdout}{run.stderr}"
