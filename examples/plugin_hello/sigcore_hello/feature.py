"""The ``hello`` feature: ``<plugin name="hello" greeting="hi" period="0.5"/>``."""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field, field_validator

from sigcore.feature import Feature, FeatureConfig

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation


class HelloConfig(FeatureConfig):
    """The attributes of ``<plugin name="hello">``; sigcore validates them and reports each problem located."""

    greeting: str = Field(description="the text to broadcast, not blank")
    period: float = Field(default=1.0, gt=0.0, description="time between two greetings in [s]")

    @field_validator("greeting")
    @classmethod
    def _not_blank(cls, value: str) -> str:
        if not value.strip():
            raise ValueError("the greeting is blank; valid: some text, e.g. 'hi'")
        return value


class HelloFeature(Feature):
    """Counts the simulation's steps and broadcasts ``greeting`` to every agent each ``period`` seconds.

    World attributes (:class:`HelloConfig`):
        greeting: The text to broadcast (required, not blank).
        period: Time between two greetings [s], > 0 (default 1). The first greeting goes out after one period.
    """

    name = "hello"
    config_model = HelloConfig
    SENDER = "hello"
    """Sender name of the greetings (not an agent, so every agent receives them)."""

    def __init__(self, sim: Simulation, config: HelloConfig) -> None:
        self.greeting = config.greeting
        self.period = config.period
        self.steps = 0
        self.sent = 0
        self._next = self.period
        sim.events.subscribe("step", self._on_step)

    def _on_step(self, sim: Simulation) -> None:
        self.steps += 1
        if sim.time >= self._next - 1e-9:
            sim.broadcast_msg(self.SENDER, self.greeting)
            self.sent += 1
            self._next += self.period

    def summary(self) -> dict[str, object]:
        """Steps counted and greetings sent."""
        return {"greeting": self.greeting, "steps": self.steps, "greetings": self.sent}
