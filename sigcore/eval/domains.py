"""ROS 2 domains for episodes: each running episode holds one ``ROS_DOMAIN_ID`` that no other episode on the machine
holds (a lock file per domain, ``flock``ed while the episode runs), so that simultaneous episodes never see each
other's nodes; discovery is limited to the machine (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``), so episodes on
other machines of a cluster cannot either. A lock dies with its process: a killed worker frees its domain."""

from __future__ import annotations

import fcntl
import os
import random
import tempfile
import time
from pathlib import Path
from types import TracebackType

DOMAINS = range(120, 233)
"""The domains episodes take (Fast DDS's ports leave 0-232; the low ones are left to people and tests)."""

LOCKS = Path(tempfile.gettempdir()) / "sigcore-domains"
"""Where the lock files are."""


class DomainLease:
    """``with DomainLease() as domain:`` a ``ROS_DOMAIN_ID`` of :data:`DOMAINS` no other lease on this machine holds
    (waits while all are held)."""

    def __init__(self, folder: Path = LOCKS) -> None:
        self.folder = folder
        self._fd: int | None = None
        self.domain: int | None = None

    def __enter__(self) -> int:
        self.folder.mkdir(parents=True, exist_ok=True)
        order = list(DOMAINS)
        random.Random(os.getpid() ^ time.monotonic_ns()).shuffle(order)  # few collisions between workers
        while True:
            for domain in order:
                fd = os.open(self.folder / f"{domain}.lock", os.O_RDWR | os.O_CREAT, 0o666)
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except OSError:
                    os.close(fd)
                    continue
                self._fd, self.domain = fd, domain
                return domain
            time.sleep(0.5)

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 trace: TracebackType | None) -> None:
        if self._fd is not None:
            fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None
