"""The bot URDF and world snippets of the MuJoCo backend tests: those of the conformance suite (one definition)."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "backends"))

from conformance_worlds import BOT_URDF, ROBOT, G, robot, run  # noqa: E402

__all__ = ["BOT_URDF", "G", "ROBOT", "robot", "run"]
