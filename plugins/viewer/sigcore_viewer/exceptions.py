"""The errors of sigcore_viewer."""

from __future__ import annotations

from sigcore.errors import SigcoreError, ViewerError


class BrowserMissing(SigcoreError, RuntimeError):
    """Chromium, its driver or selenium is not installed; the message says what to install."""


class PeerGone(ViewerError):
    """The other process closed its end (it ended, or was killed)."""


class Interrupted(ViewerError):
    """``stop()`` became true while a recording was read (Ctrl-C)."""
