"""The ROS 2 domains of the tests' processes: each pytest-xdist worker has a range of its own, so tests running at the
same time in different workers never hear each other's nodes; within a worker, successive calls rotate through the
range, so a process a previous test left behind is not heard either.

Worker ``gwK`` (``PYTEST_XDIST_WORKER``; a run without xdist is worker 0) takes ``1 + K*SPAN ... (K+1)*SPAN``, for
``K < WORKERS``: domains 1-96, away from the benches' (101-119, 150-229) and ``sigcore eval``'s (120-232)."""

from __future__ import annotations

import itertools
import os

SPAN = 24
"""Domains per worker."""
WORKERS = 4
"""Workers with disjoint ranges (a fifth worker shares the first's range)."""

_next = itertools.count()


def worker() -> int:
    """This process's xdist worker number (0 without xdist)."""
    name = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    return int(name[2:]) if name.startswith("gw") and name[2:].isdigit() else 0


def next_domain() -> int:
    """A ``ROS_DOMAIN_ID`` of this worker's range, a different one at each call (the range rotates)."""
    return 1 + (worker() % WORKERS) * SPAN + (os.getpid() + next(_next)) % SPAN
