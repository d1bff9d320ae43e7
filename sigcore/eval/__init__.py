"""Batch evaluation (``sigcore eval``): a solution over many seeded, randomised episodes, K at once on this machine
or as tasks on a Ray cluster; one row per episode in ``episodes.csv`` and a summary with 95 % intervals
(``docs/eval.md``)."""

from .episode import STATUSES, EpisodeRow, EpisodeSpec, run_episode
from .evaluation import Settings, prepare
from .exceptions import EvalError
from .results import EpisodeLog, mean_interval, summarize, wilson, write_summary
from .runner import run_local, run_ray

__all__ = ["STATUSES", "EpisodeLog", "EpisodeRow", "EpisodeSpec", "EvalError", "Settings", "mean_interval", "prepare",
           "run_episode", "run_local", "run_ray", "summarize", "wilson", "write_summary"]
