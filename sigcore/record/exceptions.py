"""The errors of recordings."""

from __future__ import annotations

from ..errors import SigcoreError


class BagError(SigcoreError, ValueError):
    """A bag cannot be written (its directory exists, is not writable) or read (missing, cut, foreign)."""


class RecordError(SigcoreError, ValueError):
    """A recording cannot start: a bad ``--record-topics`` pattern or rate, a directory that exists."""


class SerializeError(SigcoreError, ValueError):
    """A type the store does not know, or a value that does not fit its type (naming the field)."""
