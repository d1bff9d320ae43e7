"""The transport's log filter: each kind of refusal or failure of each endpoint is logged once, the rest counted.

Clients choose what they send, so nothing they send may choose how much is logged: a record is keyed on the endpoint
and the kind of error (``extra=sigcore.api.call.log_key(endpoint, kind)``), never on its text. Records without such
a key are keyed on their text with numbers blanked (start-up warnings); errors without a key always pass. The table of
keys is bounded; what is suppressed is counted and reported by :meth:`OncePerKind.summary`.
"""

from __future__ import annotations

import logging
import re
import threading
import time
from collections import Counter

MAX_KEYS = 4096
"""At most this many (endpoint, kind) keys are remembered [keys]; later kinds are counted together as 'other'."""

SUMMARY_PERIOD = 60.0
"""Suppressed records are reported at most this often [s of wall time] (and once when the transport stops)."""

SUMMARY_TOP = 5
"""A summary names the endpoints with the most suppressed records, at most this many [lines]."""

_NUMBERS = re.compile(r"[-+]?\d[\d.e+-]*|nan|inf")
_OTHER = ("(other kinds: the table of keys is full)", "")


class OncePerKind(logging.Filter):
    """Lets the first record of each (endpoint, kind) through and counts the others (thread-safe).

    Args:
        max_keys: Bound of the table of keys [keys].
    """

    def __init__(self, max_keys: int = MAX_KEYS) -> None:
        super().__init__()
        self.max_keys = max_keys
        self._seen: set[tuple[str, str]] = set()
        self._suppressed: Counter[tuple[str, str]] = Counter()
        self._lock = threading.Lock()
        self._last_summary = time.monotonic()

    def _key(self, record: logging.LogRecord) -> tuple[str, str] | None:
        endpoint = getattr(record, "endpoint", None)
        if endpoint is not None:
            return str(endpoint), str(getattr(record, "kind", ""))
        if record.levelno >= logging.ERROR or getattr(record, "summary", False):
            return None
        return record.name, _NUMBERS.sub("#", record.getMessage())[:200]

    def filter(self, record: logging.LogRecord) -> bool:
        key = self._key(record)
        if key is None:
            return True
        with self._lock:
            if key in self._seen:
                self._suppressed[key] += 1
                return False
            if len(self._seen) >= self.max_keys:
                self._suppressed[_OTHER] += 1
                return False
            self._seen.add(key)
            return True

    def summary(self, logger: logging.Logger, force: bool = False) -> None:
        """Log how many records were suppressed since the last summary, if any and if ``SUMMARY_PERIOD`` passed
        (or ``force``).

        Args:
            logger: Where to log the summary (at WARNING; it passes this filter).
            force: Report now (at the end of a run).
        """
        if not self._suppressed:
            return
        now = time.monotonic()
        if not force and now - self._last_summary < SUMMARY_PERIOD:
            return
        with self._lock:
            counts, self._suppressed = self._suppressed, Counter()
        period, self._last_summary = now - self._last_summary, now
        top = counts.most_common(SUMMARY_TOP)
        named = "; ".join(f"{n} of {endpoint}" + (f" ({kind})" if kind else "") for (endpoint, kind), n in top)
        rest = sum(counts.values()) - sum(n for _, n in top)
        more = f"; {rest} more of {len(counts) - len(top)} other kinds" if rest else ""
        logger.warning("%d more refusals/failures suppressed in the last %.0f s (each kind is logged once per "
                       "endpoint): %s%s", sum(counts.values()), period, named, more, extra={"summary": True})
