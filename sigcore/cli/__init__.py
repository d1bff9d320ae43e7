"""The ``sigcore`` command line (console script ``sigcore = "sigcore.cli:main"``, and ``python -m sigcore``). It only
parses options, calls the library and prints: the app and its entry point in :mod:`.dispatch`, one module per
command or group of related commands, what they share in :mod:`.common` and :mod:`.transport`."""

from __future__ import annotations

from .dispatch import app, main

__all__ = ["app", "main"]
