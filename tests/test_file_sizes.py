"""Files by concept: no Python file under ``sigcore/`` or ``plugins/`` is over 500 lines, except a generated one
(a file whose first line says ``# Generated``; there is none today). A file that outgrows this holds more than one
concept: split it (docs/architecture.md, "Concepts, and the file to open")."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LIMIT = 500
"""Most lines of one source file [lines]."""
SKIPPED_DIRS = {"__pycache__", "build", "dist", ".venv"}


def sources() -> list[Path]:
    """The project's own Python files under sigcore/ and plugins/ (not built or installed copies)."""
    found = []
    for top in ("sigcore", "plugins"):
        for path in (ROOT / top).rglob("*.py"):
            parts = set(path.relative_to(ROOT).parts)
            if parts & SKIPPED_DIRS or any(p.endswith(".egg-info") for p in parts):
                continue
            found.append(path)
    return found


def generated(path: Path) -> bool:
    with path.open(encoding="utf-8") as f:
        return f.readline().startswith("# Generated")


def test_the_sources_are_found() -> None:
    files = sources()
    assert len(files) >= 150  # the walk sees the project (192 files when this test was written)
    assert ROOT / "sigcore" / "sim" / "simulation.py" in files


def test_no_source_file_is_over_500_lines() -> None:
    over = {str(p.relative_to(ROOT)): n for p in sources() if not generated(p)
            and (n := len(p.read_text(encoding="utf-8").splitlines())) > LIMIT}
    assert over == {}, f"over {LIMIT} lines (split by concept): {over}"
