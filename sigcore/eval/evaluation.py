"""An evaluation's settings and folder: ``eval.json`` keeps the settings, so that ``--resume`` goes on with the same
ones (and refuses others), skipping the episodes ``episodes.csv`` already holds."""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass
from pathlib import Path

from .domains import DOMAINS
from .episode import EpisodeRow, EpisodeSpec
from .exceptions import EvalError
from .results import EpisodeLog, count

SAME = ("world", "seed", "solution", "controllers", "backend")
"""Settings a resumed evaluation must share with the one it goes on with (the rest may change)."""


@dataclass(frozen=True)
class Settings:
    """What ``sigcore eval`` was asked (paths absolute).

    Attributes:
        world: The world file.
        episodes: How many episodes.
        seed: Episode i's world is drawn with seed ``seed + i``.
        solution: The solution's shell command, or None (``controllers`` alone).
        controllers: ``AGENT=CONTROLLER`` entries.
        backend: The physics backend.
        timeout: Wall-time limit per episode [s].
        pace: The simulator's pace options.
        wait_for: Topics the simulator waits for.
        cwd: The solution's working folder.
        duration: At most this much simulated time per episode [s].
        domains: The ``ROS_DOMAIN_ID`` range of the episodes, ``(LOW, HIGH)``, both included.
    """

    world: str
    episodes: int
    seed: int
    solution: str | None
    controllers: tuple[str, ...]
    backend: str
    timeout: float
    pace: tuple[str, ...]
    wait_for: tuple[str, ...]
    cwd: str
    duration: float = 3600.0
    domains: tuple[int, int] = (DOMAINS.start, DOMAINS.stop - 1)

    def spec(self, index: int, out: Path, python: str | None) -> EpisodeSpec:
        """Episode ``index``."""
        return EpisodeSpec(index, self.seed + index, self.world, str(out), self.solution, self.controllers,
                           self.backend, self.timeout, self.pace, self.wait_for, self.cwd, python,
                           self.duration, self.domains)

    def as_dict(self) -> dict[str, object]:
        """JSON-able values."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}


def prepare(out: Path, settings: Settings, resume: bool) -> list[EpisodeRow]:
    """Make ``out`` ready: a new evaluation (``out`` empty of one), or, with ``resume``, the one there with the
    same settings. The rows already recorded.

    Raises:
        EvalError: ``out`` holds an evaluation and ``resume`` is False, or holds one of other settings, or cannot
            be written.
    """
    log = EpisodeLog(out)
    saved = out / "eval.json"
    rows = log.read()
    if rows and not resume:
        raise EvalError(f"{out} holds {count(len(rows), 'episode')} of an evaluation already; valid: --resume to go "
                        "on with it, or another --out folder")
    if resume and saved.exists():
        before = json.loads(saved.read_text())
        now = settings.as_dict()
        changed = [f"{k}: {before.get(k)!r} then, {now[k]!r} now" for k in SAME if before.get(k) != now[k]]
        if changed:
            raise EvalError(f"--resume {out}: that evaluation had other settings ({'; '.join(changed)}); valid: the "
                            "same world, seed, solution, controllers and backend, or another --out folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
        tmp = out / ".eval.json.tmp"
        tmp.write_text(json.dumps(settings.as_dict(), indent=1) + "\n")
        os.replace(tmp, saved)
    except OSError as e:
        raise EvalError(f"--out {out}: cannot write there: {e}") from None
    return rows
