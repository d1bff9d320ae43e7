"""docs/python-api.md cannot fall behind the code: each of its ```python examples runs (real MuJoCo, in a fresh
interpreter from the repository's root) and prints exactly the ```text block shown under it, and every public
method of the agent handles is named on the page."""

from __future__ import annotations

import inspect
import re
import subprocess
import sys
from pathlib import Path

import pytest

from sigcore.agent import Controller, RobotObj, SimObj
from sigcore.sim import Simulation
from sigcore.sim.features import FeatureHost
from sigcore.sim.population import Entities
from sigcore.sim.worlds import Worlds

ROOT = Path(__file__).parent.parent
DOC = ROOT / "docs" / "python-api.md"
TEXT = DOC.read_text()
BLOCK = re.compile(r"```python\n(?P<code>.*?)```\n(?:prints\n```text\n(?P<out>.*?)```)?", re.S)
EXAMPLES = [(m.group("code"), m.group("out")) for m in BLOCK.finditer(TEXT)]


def test_the_page_has_examples_with_their_output() -> None:
    """The page has a runnable example per section (at least 6), each followed by the output it prints."""
    assert len(EXAMPLES) >= 6
    assert all(out is not None for _, out in EXAMPLES)


@pytest.mark.slow
@pytest.mark.parametrize("index", range(len(EXAMPLES)))
def test_example_runs_and_prints_what_the_page_shows(index: int, tmp_path: Path) -> None:
    """Example number ``index`` exits 0 (its asserts hold) and prints exactly the output shown under it."""
    code, expected = EXAMPLES[index]
    script = tmp_path / f"example_{index}.py"
    script.write_text(code)
    r = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert r.returncode == 0, f"example {index} failed:\n{code}\n{r.stderr[-3000:]}"
    assert r.stdout == expected, f"example {index} printed:\n{r.stdout}\nthe page shows:\n{expected}"


def public_members(cls: type) -> set[str]:
    """Public methods and properties defined by ``cls`` or its sigcore bases (not ``object``'s)."""
    names = set()
    for klass in cls.__mro__:
        if not klass.__module__.startswith("sigcore"):  # object's, Mapping's
            continue
        names |= {name for name, value in vars(klass).items() if not name.startswith("_")
                  and (inspect.isfunction(value) or isinstance(value, property | staticmethod))}
    return names


@pytest.mark.parametrize("cls", [SimObj, RobotObj, Controller, Simulation, Entities, FeatureHost, Worlds])
def test_every_public_method_is_on_the_page(cls: type) -> None:
    """Every public method or property of SimObj, RobotObj, Controller, the Simulation and its parts is named on the
    page as `name(` or `name`."""
    missing = sorted(n for n in public_members(cls) if f"`{n}(" not in TEXT and f"`{n}`" not in TEXT
                     and f" {n}(" not in TEXT)
    assert missing == [], f"docs/python-api.md does not name {cls.__name__}.{', '.join(missing)}"


def test_public_members_are_found() -> None:
    """The member scan sees methods, properties and static methods (so the check above can fail)."""
    assert {"position", "time", "angle_to_axis"} <= public_members(SimObj)
    assert {"grasp", "set_base_velocity", "position"} <= public_members(RobotObj)
