"""An evaluation's results: ``episodes.csv`` (one row per episode, appended as each ends, so an interrupted
evaluation loses nothing it recorded) and ``summary.json`` (success rate and mean score with 95 % intervals,
failures by kind)."""

from __future__ import annotations

import csv
import json
import math
import os
import statistics
from dataclasses import fields
from pathlib import Path

from .episode import STATUSES, EpisodeRow
from .exceptions import EvalError

COLUMNS = [f.name for f in fields(EpisodeRow)]
"""The columns of ``episodes.csv``, in order."""

_T975 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262, 10: 2.228,
         12: 2.179, 15: 2.131, 20: 2.086, 25: 2.060, 30: 2.042, 40: 2.021, 60: 2.000, 120: 1.980}
"""Student's t, 97.5 % quantile, by degrees of freedom (between entries the next lower one is taken: wider)."""


class EpisodeLog:
    """``episodes.csv`` in an evaluation's folder: read what is there, append rows as episodes end."""

    def __init__(self, folder: Path) -> None:
        self.path = folder / "episodes.csv"

    def read(self) -> list[EpisodeRow]:
        """The rows recorded so far (none without the file).

        Raises:
            EvalError: the file is not an evaluation's ``episodes.csv`` (its columns differ).
        """
        if not self.path.exists():
            return []
        with open(self.path, newline="") as f:
            reader = csv.DictReader(f)
            if reader.fieldnames != COLUMNS:
                raise EvalError(f"{self.path}: its columns are {reader.fieldnames}; valid: {', '.join(COLUMNS)} "
                                "(the file of another program or version: use another --out)")
            return [_row(record) for record in reader if record.get("episode")]

    def append(self, row: EpisodeRow) -> None:
        """Add ``row``, on disk before this returns."""
        new = not self.path.exists() or self.path.stat().st_size == 0
        with open(self.path, "a", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=COLUMNS)
            if new:
                writer.writeheader()
            writer.writerow({k: "" if v is None else v for k, v in row.as_dict().items()})
            f.flush()
            os.fsync(f.fileno())


def _row(record: dict[str, str]) -> EpisodeRow:
    return EpisodeRow(episode=int(record["episode"]), seed=int(record["seed"]), status=record["status"],
                      success=record["success"] == "True", result=record["result"], score=_float(record["score"]),
                      events=record["events"], sim_time=_float(record["sim_time"]),
                      wall_time=_float(record["wall_time"]) or 0.0, sim_exit=_int(record["sim_exit"]),
                      solution_exit=_int(record["solution_exit"]), domain=_int(record["domain"]),
                      host=record["host"], reason=record["reason"], folder=record["folder"])


def _float(text: str) -> float | None:
    return None if text == "" else float(text)


def _int(text: str) -> int | None:
    return None if text == "" else int(text)


def wilson(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The 95 % Wilson score interval of a success rate (``(0, 1)`` for n = 0)."""
    if n == 0:
        return 0.0, 1.0
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def mean_interval(values: list[float]) -> tuple[float, float] | None:
    """Mean and the half-width of its 95 % t interval (0 for one value); None for no values."""
    if not values:
        return None
    n = len(values)
    mean = sum(values) / n
    if n == 1:
        return mean, 0.0
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1))
    df = n - 1
    t = _T975[max(k for k in _T975 if k <= df)] if df < 120 else 1.96
    return mean, t * sd / math.sqrt(n)


def count(n: int, noun: str) -> str:
    """``1 episode``, ``2 episodes``: ``n`` and ``noun``, plural unless ``n`` is 1."""
    return f"{n} {noun}{'' if n == 1 else 's'}"


def never_ran(row: EpisodeRow) -> bool:
    """Whether the episode's simulation never left t = 0 (``not_started``, or a solution that crashed before the
    simulation played): its score says nothing of the solution's work and is left out of the mean."""
    return row.status == "not_started" or row.sim_time == 0


def summarize(rows: list[EpisodeRow], planned: int) -> dict[str, object]:
    """The summary of ``rows``.

    Every episode counts in the success rate (one that never started did not succeed). The score's statistics are
    over the episodes with a score whose simulation ran (left t = 0); ``score_excluded`` counts the others.

    Returns:
        ``episodes``, ``planned``, ``succeeded``; ``success_rate`` [0-1] and ``success_interval_95`` (Wilson,
        ``{"low", "high"}``); ``score_mean`` with ``score_interval_95`` (Student's t, ``{"low", "high"}``),
        ``score_median``, ``score_min``, ``score_max``, ``scored_episodes`` (how many are in them) and
        ``score_excluded`` (``never_ran``: never left t = 0; ``no_score``: no score in the results); the mean
        simulated time (of the episodes that ran) and wall time [s]; ``failures`` (episodes by status other than
        ``done``) and ``results`` (episodes by the task's result).
    """
    n = len(rows)
    wins = sum(r.success for r in rows)
    low, high = wilson(wins, n)
    scores = [r.score for r in rows if r.score is not None and not never_ran(r)]
    score = mean_interval(scores)
    walls = mean_interval([r.wall_time for r in rows])
    sims = mean_interval([r.sim_time for r in rows if r.sim_time is not None and not never_ran(r)])
    results: dict[str, int] = {}
    for r in rows:
        if r.result:
            results[r.result] = results.get(r.result, 0) + 1
    return {
        "episodes": n, "planned": planned, "succeeded": wins,
        "success_rate": wins / n if n else None, "success_interval_95": {"low": low, "high": high},
        "score_mean": score[0] if score else None,
        "score_interval_95": {"low": score[0] - score[1], "high": score[0] + score[1]} if score else None,
        "score_median": statistics.median(scores) if scores else None,
        "score_min": min(scores) if scores else None, "score_max": max(scores) if scores else None,
        "scored_episodes": len(scores),
        "score_excluded": {"never_ran": sum(r.score is not None and never_ran(r) for r in rows),
                           "no_score": sum(r.score is None for r in rows)},
        "sim_time_mean": sims[0] if sims else None, "wall_time_mean": walls[0] if walls else None,
        "failures": {kind: sum(r.status == kind for r in rows) for kind in STATUSES if kind != "done"},
        "results": results,
    }


def write_summary(folder: Path, summary: dict[str, object], settings: dict[str, object]) -> Path:
    """``summary.json`` (the summary and the evaluation's settings), written whole or not at all."""
    path = folder / "summary.json"
    tmp = folder / ".summary.json.tmp"
    tmp.write_text(json.dumps({**summary, "settings": settings}, indent=1) + "\n")
    os.replace(tmp, path)
    return path
