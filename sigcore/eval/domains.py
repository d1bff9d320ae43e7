"""ROS 2 domains for episodes: each running episode holds one ``ROS_DOMAIN_ID`` of the evaluation's range that no
other episode on the machine holds (a lock file per domain, ``flock``ed while the episode runs), so that simultaneous
episodes never see each other's nodes; discovery is limited to the machine
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``), so episodes on other machines of a cluster cannot either. A lock
dies with its process: a killed worker frees its domain.

The range is ``sigcore eval --domains LOW-HIGH`` (or the environment variable :data:`ENV`), default
:data:`DOMAINS`, so that a team on a shared machine stays in the domains it was given."""

from __future__ import annotations

import fcntl
import os
import random
import re
import tempfile
import time
from pathlib import Path
from types import TracebackType

from .exceptions import EvalError

MAX_DOMAIN = 232
"""The largest ``ROS_DOMAIN_ID`` (Fast DDS's ports, 7400 + 250 x domain + ..., stay below 65536 up to 232)."""

DOMAINS = range(120, MAX_DOMAIN + 1)
"""The domains episodes take by default: 120-232 (the low ones are left to people and tests)."""

ENV = "SIGCORE_EVAL_DOMAINS"
"""The environment variable that gives the range when ``--domains`` is not given."""

LOCKS = Path(tempfile.gettempdir()) / "sigcore-domains"
"""Where the lock files are."""

VALID = (f"LOW-HIGH with 0 <= LOW <= HIGH <= {MAX_DOMAIN} (ROS 2 domain IDs), e.g. 120-232 or 40-49, or one "
         "domain N")


def parse_domains(text: str) -> range:
    """The domains ``LOW-HIGH`` (both included) or ``N`` names.

    Args:
        text: ``"LOW-HIGH"`` or ``"N"``, integers (spaces around them allowed).

    Raises:
        EvalError: ``text`` is not of that form, LOW > HIGH, or a domain is outside 0-232; the message names the
            valid form.
    """
    match = re.fullmatch(r"\s*([0-9]+)\s*(?:-\s*([0-9]+)\s*)?", text)
    if match is None:
        raise EvalError(f"'{text}' is not a range of ROS 2 domains; valid: {VALID}")
    low = int(match[1])
    high = int(match[2]) if match[2] is not None else low
    if low > high:
        raise EvalError(f"'{text}': LOW {low} is above HIGH {high}; valid: {VALID}")
    if high > MAX_DOMAIN:
        raise EvalError(f"'{text}': domain {high} is above {MAX_DOMAIN}, the largest ROS 2 domain ID; valid: {VALID}")
    return range(low, high + 1)


def describe(domains: range) -> str:
    """``LOW-HIGH`` (or ``N``) for ``domains``, as :func:`parse_domains` reads it."""
    return f"{domains.start}" if len(domains) == 1 else f"{domains.start}-{domains.stop - 1}"


class DomainLease:
    """``with DomainLease() as domain:`` a ``ROS_DOMAIN_ID`` of ``domains`` no other lease on this machine holds
    (waits while all are held).

    Args:
        domains: The domains to take one of (default :data:`DOMAINS`).
        folder: Where the lock files are.
    """

    def __init__(self, domains: range = DOMAINS, folder: Path = LOCKS) -> None:
        self.domains = domains
        self.folder = folder
        self._fd: int | None = None
        self.domain: int | None = None

    def __enter__(self) -> int:
        self.folder.mkdir(parents=True, exist_ok=True)
        order = list(self.domains)
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
