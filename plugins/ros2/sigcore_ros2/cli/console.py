"""How a ``sigcore ros`` command ends on failure: one line on the shared stderr console and an exit status (2 bad
input, 1 what happened, 130 Ctrl-C), never a traceback; a closed stdout (``| head``) ends it quietly."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager

import typer
from rich.console import Console

from ..exceptions import RosToolError

err = Console(stderr=True, highlight=False, markup=False, soft_wrap=True)
"""Where the ``sigcore ros`` commands print errors and warnings."""


@contextmanager
def command_errors(name: str) -> Iterator[None]:
    """Turn a :class:`RosToolError` into one line on stderr and its exit status; a closed stdout ends quietly."""
    try:
        yield
    except RosToolError as e:
        err.print(f"sigcore ros {name}: {e}")
        raise typer.Exit(e.code) from None
    except KeyboardInterrupt:  # Ctrl-C before the command's own handler was installed (while rclpy starts)
        raise typer.Exit(130) from None
    except BrokenPipeError:  # `sigcore ros echo ... | head`: the reader went away
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        raise typer.Exit(0) from None
