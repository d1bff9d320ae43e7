"""Worlds that come and go while the process runs (``sim.worlds``): load, unload, the worlds available, and the
time of every world loaded so far. A load or unload emits ``world`` on the event hub (``unloading``, then
``loaded``)."""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from .. import plugins
from ..agent.controller import resolve_controller
from ..agent.exceptions import ApiError
from ..backend import Backend
from ..errors import BackendError
from ..isolation import USER_ERRORS
from ..world.exceptions import WorldError, WorldIssue
from ..world.models import World
from ..world.resources import RefusalCode
from .exceptions import FeatureError
from .spawn import WorldChange

if TYPE_CHECKING:
    from ..world.catalogue import WorldResource
    from .simulation import Simulation

log = logging.getLogger("sigcore")

Build = Callable[[World, Backend, Mapping[str, str], bool], None]


class Worlds:
    """The world of a simulation over the process's life.

    Args:
        sim: The simulation.
        backend_class: The backend each world is built on (a new instance per world).
        first: The world the simulation was created with.
        controllers: The controllers given at construction instead of the first world's.
        build: Builds everything of a world (``world, backend, controllers, notify``): the simulation's own.
        discard: Drops everything of the current world; what lasts across worlds stays.
        started: Calls the new world's controllers' ``on_init`` (and first ``on_action``) if the run has started.
    """

    def __init__(self, sim: Simulation, backend_class: type[Backend], first: World, controllers: Mapping[str, str],
                 build: Build, discard: Callable[[], None], started: Callable[[], None]) -> None:
        self._sim = sim
        self._backend_class = backend_class
        self._first_source: Path | None = first.source if first.source.is_file() else None
        self._first_controllers = dict(controllers)
        self._build = build
        self._discard = discard
        self._started = started
        self._loaded = True
        self._sources: tuple[Path, ...] = ()
        self._steps_before = 0  # steps and simulated time of the worlds unloaded so far
        self._time_before = 0.0

    @property
    def loaded(self) -> bool:
        """False after :meth:`unload` until a world is loaded: nothing steps, entities are none."""
        return self._loaded

    @property
    def sources(self) -> tuple[Path, ...]:
        """World files and folders :meth:`available` lists besides ``worlds/`` (``sigcore run --worlds``)."""
        return self._sources

    @sources.setter
    def sources(self, sources: Sequence[str | Path]) -> None:
        self._sources = tuple(Path(p) for p in sources)

    @property
    def first_controllers(self) -> Mapping[str, str]:
        """The controllers given at construction instead of the world file's (a recording keeps them); a copy."""
        return dict(self._first_controllers)

    @property
    def elapsed_steps(self) -> int:
        """Steps taken since the simulation was created, in every world loaded so far."""
        return self._steps_before + self._sim.step_count

    @property
    def elapsed_time(self) -> float:
        """Simulated time since the simulation was created, in every world loaded so far [s]."""
        return self._time_before + self._sim.time

    def available(self, sources: Sequence[str | Path] = ()) -> tuple[list[WorldResource], list[str]]:
        """The worlds :meth:`load` may load (``sigcore.world.catalogue``): the current one, the one the run
        started with, ``worlds/``, :attr:`sources`, the plugins', and ``sources`` (files or folders).

        Returns:
            The worlds, and one line per source that does not exist or is no world file.
        """
        from ..world.catalogue import default_sources, find_worlds

        world = self._sim.world
        current = [p for p in (world.source if self._loaded else None, self._first_source) if p is not None]
        found = default_sources(current, list(self._sources), plugins.worlds()) + [(Path(p), "request")
                                                                                   for p in sources]
        return find_worlds(found)

    def load(self, world: World) -> None:
        """Replace the running world by ``world`` (between steps; the process, the transports and their nodes stay):
        the old world is unloaded (:meth:`unload`), then everything of the new one is built as a new
        :class:`~sigcore.sim.simulation.Simulation` would: backend, agents and their controllers (the world
        file's), features, publications. The new world is paused at time 0 (``step_count`` starts again;
        :attr:`elapsed_steps` goes on), as simulation_interfaces' LoadWorld leaves it "stopped"; the ``world``
        channel is emitted (``unloading``, then ``loaded``).

        Raises:
            WorldRefusal: RESOURCE_PARSE_ERROR when a controller or ``<plugin>`` of ``world`` cannot be created
                (located; found before anything is unloaded when it can be: an unknown controller or plugin name,
                plugin attributes), OPERATION_FAILED when building it failed later; no world is loaded then.
        """
        from ..world.exceptions import WorldRefusal

        self._check_loadable(world)
        self._teardown(notify=self._loaded)
        try:
            self._build(world, self._backend_class(), {}, True)
        except (WorldError, BackendError, FeatureError, ApiError) as e:
            log.error("world '%s' could not be built: %s", world.name, e)
            self._teardown(notify=False)
            self._set_no_world()
            code: RefusalCode = "RESOURCE_PARSE_ERROR" if isinstance(e, WorldError) else "OPERATION_FAILED"
            raise WorldRefusal(code, f"world '{world.name}' ({world.source}) could not be built, no world is loaded "
                                     f"now: {e}") from None
        self._loaded = True
        self._ready()
        log.info("loaded world '%s' (%s): %d entities", world.name, world.source, len(self._sim.entities.names))
        self._sim.events.emit("world", WorldChange("loaded", world))

    def unload(self) -> None:
        """Remove the running world (between steps): every entity, controller, feature and publication of it goes
        (its features' report lines are logged first); :attr:`loaded` is False until :meth:`load`, and
        nothing steps meanwhile.

        Raises:
            WorldRefusal: NO_WORLD_LOADED when none is.
        """
        from ..world.exceptions import WorldRefusal

        if not self._loaded:
            raise WorldRefusal("NO_WORLD_LOADED", "no world is loaded; load one first (load_world)")
        name = self._sim.world.name
        self._teardown()
        self._set_no_world()
        log.info("unloaded world '%s'", name)

    def _check_loadable(self, world: World) -> None:
        """Refuse ``world`` before anything is torn down when its controllers or plugins cannot be created."""
        from ..world.exceptions import WorldRefusal
        from ..world.plugin_config import plugin_issue, validate_plugin

        registered = plugins.controllers()
        issues: list[WorldIssue] = []
        for agent in world.agents:
            if agent.controller is None:
                continue
            try:
                resolve_controller(agent.controller, registered)
            except USER_ERRORS as e:  # ControllerError, or importing its module raised
                ln, col = world.location(agent.name, "controller")
                issues.append(WorldIssue(world.source, ln, col, agent.kind, "controller",
                                         f"agent '{agent.name}': {e}"))
        for cfg in world.plugins:
            try:
                validate_plugin(world, cfg, plugins.get_feature(cfg.name).config_model)
            except plugins.PluginError as e:
                issues.append(plugin_issue(world, cfg, "name", str(e)))
            except WorldError as e:
                issues.extend(e.issues)
            except USER_ERRORS:
                pass  # the feature's own validator failed: reported when it is created
        if issues:
            raise WorldRefusal("RESOURCE_PARSE_ERROR", "; ".join(str(i) for i in issues[:4]))

    def _teardown(self, notify: bool = True) -> None:
        sim = self._sim
        if notify:
            sim.events.emit("world", WorldChange("unloading", sim.world))
            for line in sim.features.report_lines():
                log.info("world '%s' at its end: %s", sim.world.name, line)
        self._steps_before += sim.step_count
        self._time_before += sim.time
        self._discard()

    def _set_no_world(self) -> None:
        """The state without a world: no entities, features or publications, paused."""
        self._build(World(name="none", source=Path("<no world>")), self._backend_class(), {}, False)
        self._loaded = False
        self._ready()

    def _ready(self) -> None:
        """A world was just set up while the process runs: paused at its time 0; its controllers' ``on_init``
        (and first ``on_action``) now if the run has started."""
        self._sim.control.hold()
        self._started()
