"""Batch evaluation (``sigcore eval``): a solution over many seeded, randomised episodes, K at once on this machine
or as tasks on a Ray cluster; one row per episode in ``episodes.csv`` and a summary with 95 % intervals
(``docs/eval.md``)."""

from .domains import DOMAINS, ENV, parse_domains
from .episode import STATUSES, EpisodeRow, EpisodeSpec, run_episode
from .evaluation import Settings, prepare
from .exceptions import EvalError
from .progress import Eta
from .results import EpisodeLog, count, mean_interval, never_ran, summarize, wilson, write_summary
from .runner import run_local, run_ray

__all__ = ["DOMAINS", "ENV", "STATUSES", "EpisodeLog", "EpisodeRow", "EpisodeSpec", "Eta", "EvalError", "Settings",
           "count", "mean_interval", "never_ran", "parse_domains", "prepare", "run_episode", "run_local", "run_ray",
           "summarize", "wilson", "write_summary"]
