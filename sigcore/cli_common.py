"""What every ``sigcore`` command shares: its two consoles and how it fails."""

from __future__ import annotations

import typer
from rich.console import Console

out = Console(highlight=False, soft_wrap=True, markup=False)
"""Standard output: results, tables, reports."""
err = Console(stderr=True, highlight=False, markup=False, soft_wrap=True)
"""Standard error: progress and problems, one line per message, never wrapped."""


def fail(lines: list[str], code: int = 2) -> typer.Exit:
    """Print ``lines`` on standard error and return the exit to raise (``raise fail([...])``): 2 for bad input (the
    default), 1 for what happened, 3 for a run that stopped early."""
    for line in lines:
        err.print(line, markup=False, soft_wrap=True)
    return typer.Exit(code)
