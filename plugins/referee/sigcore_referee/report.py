"""The referee's final score table as text lines."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .referee import Referee


def report_lines(referee: Referee) -> list[str]:
    """A table of every event (time, kind, points, running total, text) under a one-line verdict."""
    end = referee.end_time if referee.end_time is not None else referee.sim.time
    verdict = referee.result if referee.finished else "not finished"
    lines = [f"referee ({referee.config.rules} rules): {verdict} at t = {end:.2f} s, score {referee.score}"]
    if not referee.events:
        return [*lines, "  (no events)"]
    lines.append(f"  {'time [s]':>9}  {'event':<11}  {'points':>6}  {'total':>6}  what")
    total = 0
    for e in referee.events:
        total += e.points
        lines.append(f"  {e.time:9.2f}  {e.kind:<11}  {e.points:+6d}  {total:6d}  {e.text}")
    by_kind: dict[str, tuple[int, int]] = {}
    for e in referee.events:
        n, p = by_kind.get(e.kind, (0, 0))
        by_kind[e.kind] = (n + 1, p + e.points)
    parts = [f"{kind} {n}x {p:+d}" for kind, (n, p) in by_kind.items() if kind != "end"]
    lines.append(f"  total {referee.score}: {', '.join(parts) or 'nothing scored'}")
    return lines
