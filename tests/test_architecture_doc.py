"""docs/architecture.md cannot point at files that are gone: every path in its "concept -> file" table exists, and
the table names the simulation's parts."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOC = (ROOT / "docs" / "architecture.md").read_text()


def table() -> list[tuple[str, list[str]]]:
    """The rows of the table under "## Concepts, and the file to open": (concept, the paths it names)."""
    section = DOC.split("## Concepts, and the file to open", 1)[1].split("\n## ", 1)[0]
    rows = []
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 2 or cells[0] in ("concept", "---"):
            continue
        rows.append((cells[0], re.findall(r"`([^`]+)`", cells[1])))
    return rows


def resolve(path: str, previous: Path | None) -> Path:
    """A path as the table writes it: from the repository's root, or a bare file name in the folder of the path
    before it in the same cell."""
    if "/" in path.rstrip("/") or previous is None:
        return ROOT / path
    return previous.parent / path


def test_every_file_in_the_table_exists() -> None:
    rows = table()
    assert len(rows) >= 20
    missing = []
    for concept, paths in rows:
        previous = None
        for path in paths:
            target = resolve(path, previous)
            if not target.exists():
                missing.append(f"{concept}: {path}")
            previous = target
    assert missing == []


def test_the_table_names_the_parts_of_the_simulation() -> None:
    named = {p for _, paths in table() for p in paths}
    for part in ("sigcore/sim/population.py", "sigcore/sim/features.py", "sigcore/sim/worlds.py",
                 "sigcore/sim/control.py", "sigcore/sim/events.py"):
        assert part in named
    assert "```mermaid" in DOC.split("## Concepts", 1)[0]  # the picture of the layers and the hub comes first
