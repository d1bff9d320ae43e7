"""House rules: ruff and mypy are clean (run as part of the test command, so CI runs them)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).parent.parent


def _tool(name: str) -> str:
    path = Path(sys.executable).parent / name
    if not path.exists():
        found = shutil.which(name)
        if found is None:
            pytest.skip(f"{name} is not installed (scripts/setup.sh installs it)")
        return found
    return str(path)


def test_ruff_clean() -> None:
    """ruff finds nothing in the repository."""
    r = subprocess.run([_tool("ruff"), "check", "."], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_mypy_clean_on_the_core() -> None:
    """mypy finds nothing in the core package."""
    r = subprocess.run([_tool("mypy"), "sigcore"], cwd=ROOT, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
