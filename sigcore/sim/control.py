"""Requests from outside the simulation loop."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class RunControl:
    """Requests from outside the loop (a transport, a signal handler): pause, resume, step N, stop, reset."""

    paused: bool = False
    lockstep: bool = False
    pending_steps: int = 0
    stop: bool = False
    reset: bool = False
