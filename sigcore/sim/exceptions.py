"""Errors of the simulation."""

from __future__ import annotations

from ..errors import SigcoreError
from ..isolation import describe


class SimulationError(SigcoreError, RuntimeError):
    """The simulation cannot do what was asked (e.g. build a world, or step after it was closed)."""


class FeatureError(SimulationError):
    """A feature named in the world raised while being created, for a reason other than its attributes (those are
    reported as a located :class:`~sigcore.world.WorldError`).

    Attributes:
        feature: The feature's name (``<plugin name="...">``).
        where: ``file:line`` of its ``<plugin>`` element.
        cause: What the feature's constructor raised (``SystemExit`` too: a feature calling ``sys.exit``).
    """

    def __init__(self, feature: str, where: str, cause: BaseException) -> None:
        self.feature, self.where, self.cause = feature, where, cause
        super().__init__(f"{where}: feature '{feature}' failed while being created: {describe(cause)}")


class RunStateError(SigcoreError, ValueError):
    """A verb of the run control (``sigcore.sim.control.RunControl``) cannot be done now or with that value (no world
    is loaded; steps that are not a whole number of at least 1; a pace that is not a positive number); the message
    says what would be valid."""


class ReplayError(SigcoreError, ValueError):
    """An input cannot be applied again (an unknown kind or entry, a kind not replayed yet, one recorded without its
    arguments, a spawn, delete or entity information change that does not give what it gave when recorded)."""


class VideoError(SigcoreError, ValueError):
    """A video cannot be made: an unknown camera, an unwritable path, a missing encoder, a bad frame rate."""
