"""Errors of an evaluation (``sigcore eval``)."""

from __future__ import annotations

from ..errors import SigcoreError


class EvalError(SigcoreError):
    """An evaluation cannot start or go on: its settings, its folder, the Ray cluster; the message says what to
    change."""
