"""Every extension point of sigcore, in one module.

Plugins implement these with ``@sigcore.hookimpl`` (a function of the same name taking a subset of the
arguments) and are found through entry points of group ``sigcore`` (see :mod:`sigcore.plugins` and
``docs/plugins.md``).

Registration hooks receive a ``register`` callback, so one plugin may add several things and the host keeps
the registry. They are called once per plugin, on their own, when it is loaded (the first time anything
looks a name up), never per simulation. A registration hook that raises, or hands ``register`` something
invalid, disables its whole plugin, which ``sigcore plugins`` then shows with the error; the others still
load.

World-level event hooks are coarse; per-agent, per-step work is never a hook (a pluggy call costs about 2 µs,
a physics step about 60 µs): a feature that needs every step subscribes to the simulation's ``step`` event
(``sim.events.subscribe("step", fn)``, ``sigcore.sim.events``) in its constructor. These hooks are for plugins that
are not features (they outlive worlds); a feature hears of its world through ``sim.events`` only.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import pluggy

if TYPE_CHECKING:
    from pathlib import Path

    from .agent.controller import Controller
    from .backend import Backend
    from .feature import Feature
    from .sim.simulation import Simulation
    from .transport import Transport
    from .viewer import Viewer
    from .world.models import Spawnable, World

hookspec = pluggy.HookspecMarker("sigcore")

# ------------------------------------------------------------------------------------------------------------
# Registration hooks (called once per plugin when it is loaded)
# ------------------------------------------------------------------------------------------------------------


@hookspec
def sigcore_register_backends(register: Callable[[type[Backend]], None]) -> None:
    """Register physics backends: call ``register(BackendClass)`` for each.

    The class must subclass :class:`sigcore.backend.Backend`, implement every abstract method, and set the
    class attribute ``name`` (its key, e.g. ``"mujoco"``, as in ``Simulation(world, "mujoco")`` and
    ``sigcore run --backend mujoco``).
    """


@hookspec
def sigcore_register_transports(register: Callable[[type[Transport]], None]) -> None:
    """Register transports: call ``register(TransportClass)`` for each.

    The class must subclass :class:`sigcore.transport.Transport` and set ``name`` (e.g. ``"ros2"``, used by
    ``sigcore run --transport ros2``).
    """


@hookspec
def sigcore_register_features(register: Callable[[type[Feature]], None]) -> None:
    """Register world features: call ``register(FeatureClass)`` for each.

    The class must subclass :class:`sigcore.feature.Feature` and set ``name``; a world enables it with
    ``<plugin name="NAME" attr="value" .../>`` and the simulation constructs it with those attributes.
    """


@hookspec
def sigcore_register_viewers(register: Callable[[type[Viewer]], None]) -> None:
    """Register viewers: call ``register(ViewerClass)`` for each.

    The class must subclass :class:`sigcore.viewer.Viewer` and set ``name`` (e.g. ``"web"``); ``sigcore run
    --viewer`` and ``sigcore view`` start the one called :data:`sigcore.viewer.DEFAULT_VIEWER` beside the
    transport.
    """


@hookspec
def sigcore_register_controllers(register: Callable[[str, type[Controller]], None]) -> None:
    """Register controller classes under short names: ``register("cleanup.moderator", ModeratorController)``.

    The class must subclass :class:`sigcore.agent.Controller`. A world attaches one with
    ``controller="cleanup.moderator"``; prefix names with the plugin's name to avoid clashes.
    """


@hookspec
def sigcore_register_spawnables(register: Callable[[Spawnable], None]) -> None:
    """Register spawnable models: call ``register(Spawnable(name, description, element, base))`` for each.

    A spawn request names one as ``model://NAME``; ``get_spawnables`` and ``sigcore spawnables`` list them with
    the folders of ``worlds/models`` (:mod:`sigcore.world.spawnables`). ``element`` is one world-format
    ``<robot>``, ``<object>`` or ``<human>``, its relative paths starting at ``base`` (e.g. the plugin's package
    folder); ``origin`` is set to the plugin's name. A name the plugin registers twice disables the plugin; a name
    another plugin registered first is ignored with a warning naming both; an element that does not validate is
    left out of the list with a warning.
    """


@hookspec
def sigcore_register_worlds(register: Callable[[Path], None]) -> None:
    """Register worlds that ``load_world`` may load: call ``register(path)`` with a world file or a folder of them.

    ``get_available_worlds`` and ``sigcore worlds`` list them after the current world, ``worlds/`` and the command
    line's (:mod:`sigcore.world.catalogue`); a folder contributes each ``*.xml`` directly in it whose root is
    ``<world>``. A path the plugin registers twice disables the plugin; one that does not exist is listed as a
    problem of the catalogue, not an error.
    """


@hookspec
def sigcore_register_commands(cli: Any) -> None:
    """Add sub-commands to the ``sigcore`` typer app ``cli`` (a ``typer.Typer``): ``@cli.command()``.

    Called by the ``sigcore`` command line at start-up, after the plugins are loaded.
    """


# ------------------------------------------------------------------------------------------------------------
# World-level events (called in every loaded plugin that implements them)
# ------------------------------------------------------------------------------------------------------------


@hookspec
def sigcore_world_loaded(world: World) -> None:
    """A :class:`~sigcore.sim.Simulation` of ``world`` was built: backend, controllers and features, no step yet.

    Fired by the ``Simulation`` constructor itself, so a library user gets it as well as ``sigcore run`` and
    ``sigcore check``.
    """


@hookspec
def sigcore_simulation_started(simulation: Simulation) -> None:
    """A run starts: every ``on_init`` was called; steps follow.

    Fired by :meth:`Simulation.start <sigcore.sim.Simulation.start>`, which the first ``step()`` and
    :func:`sigcore.sim.run` call; once per run (again after :meth:`~sigcore.sim.Simulation.stop`).
    """


@hookspec
def sigcore_simulation_stopped(simulation: Simulation) -> None:
    """The run ended: duration reached, a stop request (QUITTING, the referee), SIGINT or SIGTERM, or an error.

    Fired by :meth:`Simulation.stop <sigcore.sim.Simulation.stop>`, which :func:`sigcore.sim.run` calls after
    stopping its transport; once per run.
    """
