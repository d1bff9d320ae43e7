"""Every extension point of sigcore, in one module.

Plugins implement these with ``@sigcore.hookimpl`` and are found through entry points of group ``sigcore``.
Registration hooks receive a ``register`` callback, so one plugin may add several things and the host keeps the
registry. World-level event hooks are coarse; per-agent, per-step work is never a hook (a pluggy call costs about
2 µs, a physics step about 60 µs): a feature that needs every step registers a step observer on the simulation.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import pluggy

if TYPE_CHECKING:
    from .backend import Backend
    from .feature import Feature
    from .sim.simulation import Simulation
    from .transport import Transport
    from .world.models import World

hookspec = pluggy.HookspecMarker("sigcore")

# -------------------------------------------------------------------------------------------------------------------
# Registration hooks
# -------------------------------------------------------------------------------------------------------------------


@hookspec
def sigcore_register_backends(register: Callable[[type[Backend]], None]) -> None:
    """Register physics backends: call ``register(BackendClass)`` for each; the class's ``name`` is its key."""


@hookspec
def sigcore_register_transports(register: Callable[[type[Transport]], None]) -> None:
    """Register transports (e.g. ROS 2): ``register(TransportClass)``; the class's ``name`` is its key."""


@hookspec
def sigcore_register_features(register: Callable[[type[Feature]], None]) -> None:
    """Register world features enabled with ``<plugin name=...>``: ``register(FeatureClass)``, keyed by ``name``."""


@hookspec
def sigcore_register_controllers(register: Callable[[str, type[Any]], None]) -> None:
    """Register controller classes under short names: ``register("cleanup.moderator", ModeratorController)``.

    A world then attaches one with ``controller="cleanup.moderator"``.
    """


@hookspec
def sigcore_register_commands(cli: Any) -> None:
    """Add sub-commands to the ``sigcore`` typer app ``cli``."""


# -------------------------------------------------------------------------------------------------------------------
# World-level events
# -------------------------------------------------------------------------------------------------------------------


@hookspec
def sigcore_world_loaded(world: World) -> None:
    """A world file was parsed and validated (before the backend builds it)."""


@hookspec
def sigcore_simulation_started(simulation: Simulation) -> None:
    """The simulation is built and its controllers initialised; steps are about to run."""


@hookspec
def sigcore_simulation_stopped(simulation: Simulation) -> None:
    """The simulation's run ended (duration reached, stopped, or interrupted)."""
