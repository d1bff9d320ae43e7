"""The ``hello`` feature: ``<plugin name="hello" greeting="hi" period="0.5"/>``."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from sigcore.feature import Feature

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation

ATTRIBUTES = ("greeting", "period")


class HelloFeature(Feature):
    """Counts the simulation's steps and broadcasts ``greeting`` to every agent each ``period`` seconds.

    World attributes:
        greeting: The text to broadcast (required, not blank).
        period: Time between two greetings [s], > 0 (default 1). The first greeting goes out after one period.
    """

    name = "hello"
    SENDER = "hello"
    """Sender name of the greetings (not an agent, so every agent receives them)."""

    def __init__(self, sim: Simulation, config: dict[str, str]) -> None:
        unknown = sorted(set(config) - set(ATTRIBUTES))
        if unknown:
            raise ValueError(f"unknown attribute '{unknown[0]}'; valid attributes: {', '.join(ATTRIBUTES)}")
        if "greeting" not in config:
            raise ValueError("attribute 'greeting' is required, e.g. greeting=\"hi\"")
        self.greeting = config["greeting"]
        if not self.greeting.strip():
            raise ValueError("attribute 'greeting' must not be blank")
        text = config.get("period", "1")
        try:
            self.period = float(text)
        except ValueError:
            raise ValueError(f"attribute 'period' must be a number of seconds, got '{text}'") from None
        if not (math.isfinite(self.period) and self.period > 0):
            raise ValueError(f"attribute 'period' must be > 0 [s], got '{text}'")
        self.steps = 0
        self.sent = 0
        self._next = self.period
        sim.add_step_observer(self._on_step)

    def _on_step(self, sim: Simulation) -> None:
        self.steps += 1
        if sim.time >= self._next - 1e-9:
            sim.broadcast_msg(self.SENDER, self.greeting)
            self.sent += 1
            self._next += self.period

    def summary(self) -> dict[str, object]:
        """Steps counted and greetings sent."""
        return {"greeting": self.greeting, "steps": self.steps, "greetings": self.sent}
