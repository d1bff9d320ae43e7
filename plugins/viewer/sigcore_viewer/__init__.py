"""sigcore's web viewer (SIGViewer's successor), built on viser: ``sigcore run WORLD --viewer``, ``sigcore view``."""

from __future__ import annotations

from collections.abc import Callable

from sigcore.plugins import hookimpl

from .viewer import WebViewer

__all__ = ["WebViewer"]


@hookimpl
def sigcore_register_viewers(register: Callable[[type], None]) -> None:
    register(WebViewer)
