"""House rules: ruff and mypy are clean (run as part of the test command, so CI runs them)."""

from __future__ import annotations

import ast
import re
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


PLUGIN_PACKAGES = sorted(p for p in (ROOT / "plugins").glob("*/sigcore_*") if p.is_dir() and p.suffix != ".egg-info")


def test_mypy_clean_on_the_core_and_every_plugin() -> None:
    """mypy finds nothing in the core package and in every bundled plugin's package."""
    assert len(PLUGIN_PACKAGES) >= 6, PLUGIN_PACKAGES
    r = subprocess.run([_tool("mypy"), "sigcore", *map(str, PLUGIN_PACKAGES)], cwd=ROOT, capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), str(path))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.add(node.module.split(".")[0])
    return found


def test_no_plugin_imports_another_plugin() -> None:
    """A plugin imports the core and itself, never another plugin: features talk to transports through the core."""
    names = {p.name for p in PLUGIN_PACKAGES}
    wrong = []
    for package in PLUGIN_PACKAGES:
        for path in package.rglob("*.py"):
            others = _imports(path) & (names - {package.name})
            wrong += [f"{path.relative_to(ROOT)} imports {other}" for other in others]
    assert not wrong, wrong


def test_the_transport_names_no_feature() -> None:
    """The ROS 2 transport's code names no feature (no features[...], no 'slam', 'referee' or 'ik' as a name)."""
    features = ("slam", "referee", "ik")
    pattern = re.compile(r"features\s*\[|features\.get\(|[\"']({})[\"']".format("|".join(features)))
    hits = []
    for path in (ROOT / "plugins" / "ros2" / "sigcore_ros2").rglob("*.py"):
        for n, line in enumerate(path.read_text().splitlines(), 1):
            if pattern.search(line):
                hits.append(f"{path.name}:{n}: {line.strip()}")
    assert not hits, hits
