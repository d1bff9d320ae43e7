"""The simulation: one world, one backend, one controller per agent, a fixed-step clock."""

from __future__ import annotations

import logging
import shutil
import tempfile
import weakref
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import plugins
from ..agent.controller import Controller, resolve_controller
from ..agent.events import CollisionEvent, Message
from ..agent.exceptions import ApiError, ControllerError
from ..agent.handle import SimObj
from ..agent.robot import RobotObj
from ..api.sources import Source
from ..api.table import ApiEntry, api_table
from ..backend import Array, Backend, BackendError
from ..feature import Feature
from ..geometry import quat_mul, quat_rotate
from ..isolation import USER_ERRORS, describe
from ..publish import Publication, Publications, Publisher
from ..scene import Scene
from ..text import quote
from ..world.exceptions import WorldError, WorldIssue
from ..world.models import Entity, Object, Robot, Spawnable, World
from ..world.resources import (
    RefusalCode,
    SpawnRefusal,
    SpawnRequest,
    build_model,
    check_pose,
    normalize_namespace,
    resource_element,
    unique_name,
)
from ..world.urdf import UrdfModel
from .camera import Cameras
from .contacts import ContactTracker, rolling_parts
from .control import RunControl
from .description import DescriptionTopics
from .dispatch import Dispatcher
from .drive import DriveState
from .events import Events, Reset, Subscriber, Subscription
from .exceptions import FeatureError
from .feature_guard import FeatureFailure, FeatureGuard, FeatureOwner
from .frames import Frames
from .grasps import Grasps
from .info import EntityInfos
from .inputs import Inputs
from .lidar import LidarSensor
from .modes import Mode, Modes
from .odometry import WheelOdometry
from .owners import Owners
from .spawn import EntityChange, WorldChange

if TYPE_CHECKING:
    from ..world.catalogue import WorldResource

log = logging.getLogger("sigcore")



class _WorldParts:
    """The owner of what one world's own parts subscribed (its description topics, its publication sources):
    detached with that world."""

    def __repr__(self) -> str:
        return "<the world's parts>"


class Simulation:
    """A running world.

    Args:
        world: The validated world.
        backend: A registered backend name (default ``"mujoco"``) or a backend instance.
        controllers: Controllers to attach instead of (or in addition to) the world file's, by agent name:
            a registered name or ``package.module:Class`` (e.g. ``{"robot_000": "cleanup.robot"}``).

    Raises:
        WorldError: a controller or feature named in the world cannot be created (located in the file).
        sigcore.plugins.PluginError: the backend is not registered.
    """

    def __init__(self, world: World, backend: str | Backend = "mujoco",
                 controllers: dict[str, str] | None = None) -> None:
        # what lasts from one world to the next (load_world): the run's control, the event hub (what transports and
        # library users subscribed), the publication contract and its sinks, the clock of the whole process
        self._backend_class: type[Backend] = (plugins.get_backend(backend) if isinstance(backend, str)
                                              else type(backend))
        self.events = Events(self._contain, self._owner_of)
        """The event hub (``sigcore.sim.events``): step, collision, message, scan, camera, entities, scene, world,
        reset, input and control; ``sim.events.subscribe(channel, fn)``."""
        self.control = RunControl(loaded=lambda: self.loaded, reset=lambda despawn: self.reset(despawn),
                                  on_change=lambda change: self.events.emit("control", change),
                                  step_count=lambda: self.step_count)
        """The run's state and its verbs (play, pause, step, request_reset, set_pace, stop; ``sigcore.sim.control``),
        which every client calls."""
        self._hooks: dict[Subscription, str] = {}  # the features' reset/entities_changed subscriptions -> hook name
        self.world_sources: list[Path] = []
        """World files and folders :meth:`available_worlds` lists besides ``worlds/`` (``sigcore run --worlds``)."""
        self.loaded = True
        """False after :meth:`unload_world` until a world is loaded: nothing steps, entities are none."""
        self._steps_before = 0  # steps and simulated time of the worlds unloaded so far (elapsed_steps/_time)
        self._time_before = 0.0
        self._sources_attached = False
        self.inputs = Inputs(self)
        """The input log: commands applied from outside (transports, viewers), for recordings and replays."""
        self.publications = Publications(lambda: self.step_count * self._dt_ns, self._attach_sources)
        self._started = False  # between start() and stop()
        self._first_source: Path | None = world.source if world.source.is_file() else None
        self.controller_overrides: dict[str, str] = dict(controllers or {})
        """The controllers given at construction instead of the world file's (a recording keeps them)."""
        self._setup(world, backend if isinstance(backend, Backend) else self._backend_class(), controllers or {})

    def _setup(self, world: World, backend: Backend, controllers: dict[str, str], notify: bool = True) -> None:
        """Build everything that belongs to ``world`` (the constructor, and :meth:`load_world` after the old world
        was torn down); ``notify``: fire ``sigcore_world_loaded`` (not for the empty world of :meth:`unload_world`)."""
        self.world = world
        self.dt = world.timestep
        self.backend: Backend = backend
        self.backend.build(world)
        self.step_count = 0
        self._models = {a.name: a for a in world.agents}
        self._drives = {r.name: DriveState(r.name, r.drive) for r in world.agents
                        if isinstance(r, Robot) and r.drive is not None}
        self.entity_names: list[str] = [e.name for e in world.entities]
        self._urdfs: dict[str, UrdfModel] = {
            r.name: world.urdf(r.name).model for r in world.agents if isinstance(r, Robot)
        }
        self.graspable: list[str] = [o.name for o in world.agents if isinstance(o, Object) and o.graspable]
        self.grasps = Grasps()
        """Who holds what (changed by ``RobotObj.grasp`` / ``release``; read by anyone)."""
        self.owners = Owners()
        self.info = EntityInfos(world.entities)
        """Category, description and tags of every entity (``set_entity_info`` changes them, a reset restores)."""
        self.services: dict[str, Callable[[str, str], None]] = {}
        self.connections: dict[str, set[str]] = {}
        self._modes = Modes(self.backend, world.entities)
        self._wrench: dict[tuple[str, str | None], list[Array]] = {}
        self._outbox: list[Message] = []
        self._contacts = ContactTracker(
            self.backend, [a.name for a in world.agents],
            {r.name: rolling_parts(r, self._urdfs[r.name]) for r in world.agents if isinstance(r, Robot)}, self.dt)
        self.agents: dict[str, SimObj] = {
            a.name: (RobotObj if isinstance(a, Robot) else SimObj)(self, a.name, a.kind) for a in world.agents
        }
        self.dispatch = Dispatcher(self.dt)
        self.lidars: list[LidarSensor] = [
            LidarSensor(r.name, lidar, self.dt, world.seed + i)
            for r in world.agents if isinstance(r, Robot) for i, lidar in enumerate(r.lidars)
        ]
        self.odometry: dict[str, WheelOdometry] = {}
        self._dt_ns = round(self.dt * 1e9)
        self._sources: list[tuple[Source, dict[str, Publisher], str | None]] = []  # (source, publishers, feature)
        self._source_slots: dict[tuple[str, str], tuple[Source, dict[str, Publisher], str | None]] = {}
        self._agent_topics: dict[str, list[str]] = {}  # agent -> the topics declared for it (withdrawn on delete)
        self.frames = Frames(self)
        self.cameras = Cameras(self)
        """Every ``<camera>`` of the robots, rendered off the simulation thread (``sigcore.sim.camera``)."""
        for robot in world.agents:
            if isinstance(robot, Robot) and robot.cameras:
                self.cameras.add(robot.name, robot.cameras)
        self.scene = Scene(world, self.backend, self.frames.name, lambda scene: self.events.emit("scene", scene))
        """Every entity's visual geometry and bounds (``sigcore.scene``); ``robot_description`` and
        ``/sigcore/scene`` are published from it."""
        self._world_parts = _WorldParts()
        with self.events.owned_by(self._world_parts):
            self.description = DescriptionTopics(self)
        self.spawned: dict[str, str] = {}
        """Entities added while running -> their namespace (``""`` or ``/ns``); ``sigcore.world.resources``."""
        self._initial_world = world
        self._spawn_dir: Path | None = None
        self._attach_controllers(controllers)
        self.features: dict[str, Feature] = {}
        self.feature_guard = FeatureGuard()
        """Which feature registered which viewer service; the features disabled while running."""
        self._feature_entries: dict[str, list[ApiEntry]] = {}
        self._creating: str | None = None  # the feature being created (its services are its own)
        self._create_features()
        self._declare_agent_publications()
        if notify:
            plugins.notify("sigcore_world_loaded", world=world)

    # ------------------------------------------------------------------ construction
    def _issue(self, agent: str, attribute: str | None, message: str, line: int | None = None) -> WorldIssue:
        if line is not None:
            return WorldIssue(self.world.source, line, 1, "plugin", attribute, message)
        ln, col = self.world.location(agent, attribute)
        return WorldIssue(self.world.source, ln, col, self._models[agent].kind, attribute, message)

    def _attach_controllers(self, overrides: dict[str, str]) -> None:
        unknown = sorted(set(overrides) - set(self.agents))
        if unknown:
            raise ApiError(f"no agent {', '.join(repr(u) for u in unknown)} to attach a controller to; agents: "
                           f"{', '.join(self.agents)}")
        registered = plugins.controllers()
        issues = []
        for agent in self.world.agents:
            spec = overrides.get(agent.name, agent.controller)
            if spec is None:
                continue
            try:
                cls = resolve_controller(spec, registered)
                controller = cls()
            except ControllerError as e:
                issues.append(self._issue(agent.name, "controller", f"agent '{agent.name}': {e}"))
                continue
            except USER_ERRORS as e:  # its constructor raised or called sys.exit
                detail = describe(e).partition(": ")[2]  # the message, or that sys.exit was called
                issues.append(self._issue(agent.name, "controller", f"controller '{spec}' of agent '{agent.name}' "
                                          f"raised {type(e).__name__} while being created: {detail}"))
                continue
            self.dispatch.add(self.agents[agent.name], controller)
        if issues:
            raise WorldError(issues)

    def set_controller(self, agent: str, controller: Controller) -> None:
        """Attach a controller instance to an agent (before the first step)."""
        if self._started:
            raise ApiError("controllers are attached before the simulation starts")
        self.dispatch.add(self.agent(agent), controller)

    def _create_features(self) -> None:
        """Validate each ``<plugin>``'s attributes against its feature's ``config_model``, then create it; every
        problem is a WorldIssue at its attribute (a ``FieldError`` from a constructor names the attribute)."""
        from ..world.exceptions import FieldError
        from ..world.plugin_config import plugin_issue, validate_plugin

        issues: list[WorldIssue] = []
        for cfg in self.world.plugins:
            try:
                cls = plugins.get_feature(cfg.name)
                config = validate_plugin(self.world, cfg, cls.config_model)
            except plugins.PluginError as e:
                issues.append(plugin_issue(self.world, cfg, "name", str(e)))
                continue
            except WorldError as e:
                issues.extend(e.issues)
                continue
            except USER_ERRORS as e:  # its config model's own validator failed: the feature's code, not the file
                raise FeatureError(cfg.name, f"{self.world.source}:{cfg.line}", e) from e
            owner = FeatureOwner(cfg.name)
            self._creating = cfg.name
            try:
                with self.events.owned_by(owner):
                    feature = self.features[cfg.name] = cls(self, config)
                self._feature_entries[cfg.name] = list(cls.api_entries())
                self._subscribe_hooks(owner, feature)
            except FieldError as e:
                issues.append(plugin_issue(self.world, cfg, e.field, str(e)))
            except (ValueError, KeyError, TypeError) as e:
                issues.append(plugin_issue(self.world, cfg, None, f"plugin '{cfg.name}': {e}"))
            except USER_ERRORS as e:  # not its attributes: the feature itself failed (or called sys.exit)
                raise FeatureError(cfg.name, f"{self.world.source}:{cfg.line}", e) from e
            finally:
                self._creating = None
            if cfg.name not in self.features:
                self.events.detach(owner)  # what a constructor that failed had subscribed
        if issues:
            raise WorldError(issues)

    def _subscribe_hooks(self, owner: FeatureOwner, feature: Feature) -> None:
        """``feature.entities_changed`` and ``feature.reset`` on the hub's ``entities`` and ``reset`` channels, owned
        by the feature (only those it overrides: the defaults do nothing)."""
        cls = type(feature)
        if cls.entities_changed is not Feature.entities_changed:
            self._hooks[self.events.subscribe("entities", feature.entities_changed, owner)] = "entities_changed"
        if cls.reset is not Feature.reset:
            def reset(_: Reset, hook: Callable[[], None] = feature.reset) -> None:
                hook()
            self._hooks[self.events.subscribe("reset", reset, owner)] = "reset"

    def _owner_of(self, fn: Subscriber) -> FeatureOwner | None:
        """The owner of a subscriber subscribed without one: the feature it is a bound method of, if any."""
        instance = getattr(fn, "__self__", None)
        return next((FeatureOwner(name) for name, feature in getattr(self, "features", {}).items()
                     if feature is instance), None)

    def _declare_agent_publications(self, agents: Iterable[str] | None = None) -> None:
        """One publication per agent (of ``agents``, default all) for every ``publish`` entry of the API table (the
        core's and the features'); an agent spawned with a namespace has its topics under it."""
        owners = {id(e): name for name, entries in self._feature_entries.items() for e in entries}
        for entry in self.api_entries():
            if entry.direction != "publish" or entry.source is None:
                continue
            key = (entry.origin, entry.suffix)
            slot = self._source_slots.get(key)
            publishers: dict[str, Publisher] = slot[1] if slot is not None else {}
            for agent in (self.agents if agents is None else agents):
                handle = self.agents[agent]
                if handle.kind in entry.kinds and entry.source.has(self, agent):
                    namespace = self.spawned.get(agent, "")
                    topic = f"{namespace}/{entry.name_for(agent)}" if namespace else entry.name_for(agent)
                    publishers[agent] = self.publications.declare(Publication(
                        topic, entry.ros_type, entry.qos, entry.doc, entry.origin, agent, entry.request))
                    self._agent_topics.setdefault(agent, []).append(topic)
            if publishers and slot is None:
                slot = (entry.source, publishers, owners.get(id(entry)))
                self._source_slots[key] = slot
                self._sources.append(slot)
                if self._sources_attached:
                    self._attach_source(*slot)

    def _attach_sources(self) -> None:
        """Attach the sources of the agents' publications (when the first sink connects); what a feature's
        source subscribes is that feature's."""
        self._sources_attached = True
        for source, publishers, feature in self._sources:
            self._attach_source(source, publishers, feature)

    def _attach_source(self, source: Source, publishers: dict[str, Publisher], feature: str | None) -> None:
        """What ``source`` subscribes is its feature's (detached if that feature is disabled), or the world's."""
        with self.events.owned_by(self._world_parts if feature is None else FeatureOwner(feature)):
            source.attach(self, publishers)

    # ------------------------------------------------------------------ run-time changes (sigcore.world.resources)
    def namespace(self, agent: str) -> str:
        """The ROS namespace of ``agent``'s endpoints: ``""`` for the world file's, ``/ns`` for one spawned with
        a namespace."""
        return self.spawned.get(agent, "")

    def spawnables(self) -> list[Spawnable]:
        """What ``model://NAME`` may name (``sigcore.world.spawnables``)."""
        from ..world.spawnables import find_spawnables

        return find_spawnables(self.world, plugins.spawnables().values())

    def _spawnable(self, name: str) -> Spawnable:
        from ..world.spawnables import spawnable

        return spawnable(self.world, name, plugins.spawnables().values())

    def spawn(self, requests: Sequence[SpawnRequest]) -> list[str | SpawnRefusal]:
        """Add entities while running (between steps): each request is resolved and validated like a world file's
        element; the valid ones are added in one backend call.

        Returns:
            Per request, the name the entity got, or the :class:`SpawnRefusal` saying why it was not added (a
            backend failure refuses every request of the call: nothing is added then).
        """
        if not self.loaded:
            return [SpawnRefusal("OPERATION_FAILED", "no world is loaded to spawn into; load one first (load_world)")
                    for _ in requests]
        results: list[str | SpawnRefusal] = []
        models: list[Entity] = []
        namespaces: dict[str, str] = {}
        taken: dict[str, str] = {**self.frames.taken(), **{a: f"agent '{a}'" for a in self.agents}}
        for request in requests:
            try:
                model, namespace = self._resolve(request, taken)
            except SpawnRefusal as refusal:
                results.append(refusal)
                continue
            taken[model.name] = "an entity of the same request"
            models.append(model)
            namespaces[model.name] = namespace
            results.append(model.name)
        if models:
            try:
                self.add_entities(models, namespaces)
            except SpawnRefusal as refusal:
                results = [refusal if isinstance(r, str) else r for r in results]
        return results

    def _resolve(self, request: SpawnRequest, taken: dict[str, str]) -> tuple[Entity, str]:
        namespace = normalize_namespace(request.namespace)
        xyz, wxyz = check_pose(request.xyz, request.wxyz)
        frame = request.frame.strip()
        if frame not in ("", "world"):
            if frame not in self.entity_names:
                raise SpawnRefusal("INVALID_POSE", f"pose frame '{frame[:80]}' is unknown; valid: 'world' (or empty) "
                                                   f"or an entity: {', '.join(self.entity_names)}")
            pos, quat = self.backend.get_pose(frame)
            xyz, wxyz = pos + quat_rotate(quat, xyz), quat_mul(quat, wxyz)
        if self._spawn_dir is None:  # URDF texts of requests, removed with the simulation
            self._spawn_dir = Path(tempfile.mkdtemp(prefix="sigcore-spawn-"))
            weakref.finalize(self, shutil.rmtree, self._spawn_dir, True)
        element, base, default = resource_element(request, self.world, self._spawn_dir, self._spawnable)
        wanted = request.name.strip() or str(element.get("name", "")).strip() or default
        name = unique_name(wanted, taken, request.allow_renaming)
        model = build_model(self.world, element, base, name, (xyz, wxyz), request.tags)
        return model, namespace

    def add_entities(self, models: Sequence[Entity], namespaces: dict[str, str] | None = None) -> list[str]:
        """Add validated entity models while running (between steps), in one backend call: every owner of
        per-entity state learns of them, their controllers are created (``on_init`` called at once when the run
        has started), the ``entities`` channel is emitted (features, transports).

        Raises:
            SpawnRefusal: a name is taken or names a TF frame in use (NAME_NOT_UNIQUE), a controller cannot be
                created (RESOURCE_PARSE_ERROR), the backend failed (OPERATION_FAILED); nothing changed then.
        """
        namespaces = namespaces or {}
        taken = {**self.frames.taken(), **{a: f"agent '{a}'" for a in self.agents}}
        names = [m.name for m in models]
        for model in models:
            if model.name in taken or names.count(model.name) > 1:
                raise SpawnRefusal("NAME_NOT_UNIQUE", f"name '{model.name}' is taken "
                                                      f"({taken.get(model.name, 'twice in this request')})")
        registered = plugins.controllers()
        controllers: dict[str, Controller] = {}
        for model in models:
            if model.controller is None:
                continue
            try:
                controllers[model.name] = resolve_controller(model.controller, registered)()
            except USER_ERRORS as e:  # ControllerError, or its constructor raised
                raise SpawnRefusal("RESOURCE_PARSE_ERROR", f"controller '{model.controller}' of '{model.name}' "
                                                           f"cannot be created: {e}") from None
        world = self.world.with_agents(self.world.agents + tuple(models))
        try:
            self.backend.add_entities(world, names)
        except BackendError as e:
            raise SpawnRefusal("OPERATION_FAILED", f"the backend could not add {', '.join(names)}: {e}") from None
        self.world = world
        for model in models:
            self._models[model.name] = model
            self.entity_names.append(model.name)
            self.spawned[model.name] = namespaces.get(model.name, "")
            self.agents[model.name] = (RobotObj if isinstance(model, Robot) else SimObj)(self, model.name, model.kind)
            if isinstance(model, Robot):
                self._urdfs[model.name] = world.urdf(model.name).model
                if model.drive is not None:
                    self._drives[model.name] = DriveState(model.name, model.drive)
                self.lidars.extend(LidarSensor(model.name, lidar, self.dt, self.world.seed + len(self.lidars) + i)
                                   for i, lidar in enumerate(model.lidars))
            if isinstance(model, Object) and model.graspable:
                self.graspable.append(model.name)
        self.info.add(models)
        self._modes.add(models)
        self._refresh_contacts()
        self.frames.add([(m.name, m.kind) for m in models])
        for model in models:
            if isinstance(model, Robot) and model.cameras:
                self.cameras.add(model.name, model.cameras, self.spawned[model.name])
        self.scene.add(world, models, self.frames.name)
        for model in models:
            if isinstance(model, Robot):
                self.description.add(model.name, self.spawned[model.name])
        self._declare_agent_publications(names)
        for name, controller in controllers.items():
            self.dispatch.add(self.agents[name], controller)
        if self._started:
            self.dispatch.init(self.time)
        log.info("spawned %s at t=%.3f s", ", ".join(f"{m.kind} '{m.name}'" for m in models), self.time)
        self._changed(EntityChange(added=tuple(names)))
        return names

    def delete(self, names: Sequence[str]) -> None:
        """Remove entities while running (between steps): grasps that involve them are released first, their
        controllers, endpoints, frames and scene entries go; entities that rested on them fall.

        Raises:
            SpawnRefusal: NOT_FOUND (no such entity; lists them), OPERATION_FAILED (a feature's ``<plugin>``
                names it, or the backend failed); nothing changed then.
        """
        names = list(dict.fromkeys(names))
        for name in names:
            if name not in self.entity_names:
                raise SpawnRefusal("NOT_FOUND", f"no entity {quote(name)} to delete; entities: "
                                                f"{', '.join(self.entity_names) or 'none'}")
            for cfg in self.world.plugins:
                if name in " ".join(cfg.config.values()).split():
                    raise SpawnRefusal("OPERATION_FAILED", f"'{name}' is named by <plugin name=\"{cfg.name}\"> "
                                                           "of the world file; it cannot be deleted while that "
                                                           "feature runs")
        gone = set(names)
        for robot, part, obj in self.grasps.items():
            if robot in gone or obj in gone:
                self.grasps.release(robot, part)
                self.backend.detach(robot, part, obj)
        world = self.world.with_agents(tuple(a for a in self.world.agents if a.name not in gone))
        try:
            self.backend.remove_entities(world, names)
        except BackendError as e:
            raise SpawnRefusal("OPERATION_FAILED", f"the backend could not remove {', '.join(names)}: {e}") from None
        self.cameras.remove(names)
        self.frames.remove(names)
        self.scene.remove(names)
        for name in names:
            if self._models[name].kind == "robot":
                self.description.remove(name)
            for topic in self._agent_topics.pop(name, []):
                self.publications.withdraw(topic)
            for _, publishers, _ in self._sources:
                publishers.pop(name, None)
            self.dispatch.remove(name)
            del self.agents[name]
            del self._models[name]
            self.entity_names.remove(name)
            self.spawned.pop(name, None)
            self._urdfs.pop(name, None)
            self._drives.pop(name, None)
            self.odometry.pop(name, None)
            if name in self.graspable:
                self.graspable.remove(name)
        self.world = world
        self.lidars = [lidar for lidar in self.lidars if lidar.robot not in gone]
        self.info.remove(names)
        self._modes.remove(names)
        self.owners.forget(gone)
        self._wrench = {k: v for k, v in self._wrench.items() if k[0] not in gone}
        self._outbox = [m for m in self._outbox if m.to not in gone]
        self._refresh_contacts()
        log.info("deleted %s at t=%.3f s", ", ".join(repr(n) for n in names), self.time)
        self._changed(EntityChange(removed=tuple(names)))

    def _refresh_contacts(self) -> None:
        robots = {a.name: a for a in self.world.agents if isinstance(a, Robot)}
        self._contacts.set_agents([a.name for a in self.world.agents],
                                  {name: rolling_parts(r, self._urdfs[name]) for name, r in robots.items()})

    def _changed(self, change: EntityChange) -> None:
        """Emit ``scene`` (the scene's version bumped), then ``entities`` (features' ``entities_changed``,
        transports)."""
        self.scene.changed()
        self.events.emit("entities", change)

    # ------------------------------------------------------------------ worlds (sigcore.world.catalogue)
    def available_worlds(self, sources: Sequence[str | Path] = ()) -> tuple[list[WorldResource], list[str]]:
        """The worlds :meth:`load_world` may load (``sigcore.world.catalogue``): the current one, the one the run
        started with, ``worlds/``, :attr:`world_sources`, the plugins', and ``sources`` (files or folders).

        Returns:
            The worlds, and one line per source that does not exist or is no world file.
        """
        from ..world.catalogue import default_sources, find_worlds

        current = [p for p in (self.world.source if self.loaded else None, self._first_source) if p is not None]
        found = default_sources(current, self.world_sources, plugins.worlds()) + [(Path(p), "request") for p in sources]
        return find_worlds(found)

    def load_world(self, world: World) -> None:
        """Replace the running world by ``world`` (between steps; the process, the transports and their nodes stay):
        the old world is unloaded (:meth:`unload_world`), then everything of the new one is built as a new
        :class:`Simulation` would: backend, agents and their controllers (the world file's), features, publications.
        The new world is paused at time 0 (``step_count`` starts again; :attr:`elapsed_steps` goes on), as
        simulation_interfaces' LoadWorld leaves it "stopped"; the ``world`` channel is emitted (``unloading``, then
        ``loaded``).

        Raises:
            WorldRefusal: RESOURCE_PARSE_ERROR when a controller or ``<plugin>`` of ``world`` cannot be created
                (located; found before anything is unloaded when it can be: an unknown controller or plugin name,
                plugin attributes), OPERATION_FAILED when building it failed later; no world is loaded then.
        """
        from ..world.catalogue import WorldRefusal

        self._check_loadable(world)
        self._teardown(notify=self.loaded)
        try:
            self._setup(world, self._backend_class(), {})
        except (WorldError, BackendError, FeatureError, ApiError) as e:
            log.error("world '%s' could not be built: %s", world.name, e)
            self._teardown(notify=False)
            self._set_no_world()
            code: RefusalCode = "RESOURCE_PARSE_ERROR" if isinstance(e, WorldError) else "OPERATION_FAILED"
            raise WorldRefusal(code, f"world '{world.name}' ({world.source}) could not be built, no world is loaded "
                                     f"now: {e}") from None
        self.loaded = True
        self._world_ready()
        log.info("loaded world '%s' (%s): %d entities", world.name, world.source, len(self.entity_names))
        self.events.emit("world", WorldChange("loaded", world))

    def unload_world(self) -> None:
        """Remove the running world (between steps): every entity, controller, feature and publication of it goes
        (its features' report lines are logged first); :attr:`loaded` is False until :meth:`load_world`, and
        nothing steps meanwhile.

        Raises:
            WorldRefusal: NO_WORLD_LOADED when none is.
        """
        from ..world.catalogue import WorldRefusal

        if not self.loaded:
            raise WorldRefusal("NO_WORLD_LOADED", "no world is loaded; load one first (load_world)")
        name = self.world.name
        self._teardown()
        self._set_no_world()
        log.info("unloaded world '%s'", name)

    def _check_loadable(self, world: World) -> None:
        """Refuse ``world`` before anything is torn down when its controllers or plugins cannot be created."""
        from ..world.catalogue import WorldRefusal
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
        """Drop everything of the current world; what lasts across worlds (control, what transports and library
        users subscribed, the publication sinks) stays."""
        if notify:
            self.events.emit("world", WorldChange("unloading", self.world))
            for line in self.report_lines():
                log.info("world '%s' at its end: %s", self.world.name, line)
        self._steps_before += self.step_count
        self._time_before += self.time
        for publication in self.publications.declared:
            self.publications.withdraw(publication.topic)
        for feature in getattr(self, "features", {}):
            self.events.detach(FeatureOwner(feature))
        self.events.detach(self._world_parts)
        self._hooks.clear()
        self.cameras.close()
        self.backend.close()

    def _set_no_world(self) -> None:
        """The state without a world: no entities, features or publications, paused."""
        self._setup(World(name="none", source=Path("<no world>")), self._backend_class(), {}, notify=False)
        self.loaded = False
        self._world_ready()

    def _world_ready(self) -> None:
        """A world was just set up while the process runs: paused at its time 0; its controllers' ``on_init``
        (and first ``on_action``) now if the run has started."""
        self.control.hold()
        if self._started:
            self.dispatch.init(self.time)
            self.dispatch.actions(self.step_count, self.time)

    @property
    def elapsed_steps(self) -> int:
        """Steps taken since the simulation was created, in every world loaded so far."""
        return self._steps_before + self.step_count

    @property
    def elapsed_time(self) -> float:
        """Simulated time since the simulation was created, in every world loaded so far [s]."""
        return self._time_before + self.time

    # ------------------------------------------------------------------ lookups used by handles and the API
    @property
    def time(self) -> float:
        """Simulation time [s]: steps taken times the timestep (a reset does not move it back)."""
        return self.step_count * self.dt

    @property
    def stamp_ns(self) -> int:
        """Simulation time [ns], exact (what publications are stamped with)."""
        return self.step_count * self._dt_ns

    def agent(self, name: str) -> SimObj:
        """Handle of an agent; ``ApiError`` listing valid names if there is none."""
        try:
            return self.agents[name]
        except KeyError:
            raise ApiError(f"no agent {quote(name)}; agents: {', '.join(self.agents)}") from None

    def robot(self, name: str) -> RobotObj:
        """Handle of a robot; ``ApiError`` listing the robots otherwise."""
        handle = self.agent(name)
        if not isinstance(handle, RobotObj):
            robots = [n for n, h in self.agents.items() if isinstance(h, RobotObj)]
            article = "an" if handle.kind[0] in "aeiou" else "a"
            raise ApiError(f"'{name}' is {article} {handle.kind}, not a robot; robots: {', '.join(robots) or 'none'}")
        return handle

    def robot_model(self, name: str) -> Robot:
        """The world model of robot ``name``."""
        model = self._models[name]
        assert isinstance(model, Robot)
        return model

    def urdf(self, robot: str) -> UrdfModel:
        """The URDF names of robot ``robot`` (of the world's shared document, ``World.urdf``)."""
        return self._urdfs[robot]

    def drive(self, robot: str) -> DriveState:
        """The differential drive of ``robot`` as it is now (geometry set by ``_setWheel``; the world file's
        ``<drive>`` is its ``model``); ``ApiError`` if it has none."""
        state = self._drives.get(robot)
        if state is None:
            raise ApiError(f"robot '{robot}' has no <drive> in the world file")
        return state

    def wheels(self, robot: str) -> tuple[float, float]:
        """``(radius, separation)`` [m] of ``robot``'s drive now in use."""
        return self.drive(robot).geometry()

    def modes(self, entity: str) -> dict[str, bool]:
        """Current gravity/dynamics/collision modes of an entity (a copy)."""
        return self._modes.of(entity)

    def mode(self, entity: str, mode: Mode) -> bool:
        """Whether ``mode`` (``gravity``, ``dynamics``, ``collision``) is on for ``entity``."""
        return self._modes.get(entity, mode)

    def set_mode(self, entity: str, mode: Mode, enabled: bool) -> None:
        """Switch ``gravity``, ``dynamics`` or ``collision`` for an entity."""
        self._modes.set(entity, mode, enabled)

    def register_service(self, name: str, handler: Callable[[str, str], None]) -> None:
        """Offer a viewer service (e.g. a referee): ``handler(sender, text)`` receives ``_send_msg_to_srv`` texts
        and raises ``ApiError`` to refuse one."""
        self.services[name] = handler
        if self._creating is not None:
            self.feature_guard.services[name] = self._creating

    # ------------------------------------------------------------------ wrenches (for the next step)
    def add_wrench(self, entity: str, part: str | None, force: Array, torque: Array) -> None:
        """Accumulate a world-frame force [N] at the part's CoM and a torque [N m] for the next step."""
        acc = self._wrench.setdefault((entity, part), [np.zeros(3), np.zeros(3)])
        acc[0] = acc[0] + force
        acc[1] = acc[1] + torque

    def set_wrench(self, entity: str, part: str | None, force: Array | None = None,
                   torque: Array | None = None) -> None:
        """Replace the force and/or torque to apply during the next step."""
        acc = self._wrench.setdefault((entity, part), [np.zeros(3), np.zeros(3)])
        if force is not None:
            acc[0] = force
        if torque is not None:
            acc[1] = torque

    # ------------------------------------------------------------------ messages
    def send_msg(self, sender: str, to: str, text: str) -> None:
        """Queue a text message for agent ``to`` (delivered before the next step)."""
        if to not in self.agents:
            raise ApiError(f"no agent {quote(to)} to send to; agents: {', '.join(self.agents)}")
        if not isinstance(text, str):
            raise ApiError(f"message text must be a string, got {type(text).__name__}")
        self._outbox.append(Message(sender, to, text, self.time))

    def broadcast_msg(self, sender: str, text: str) -> None:
        """Queue ``text`` for every agent except ``sender``."""
        for name in self.agents:
            if name != sender:
                self.send_msg(sender, name, text)

    def deliver_messages(self) -> None:
        """Deliver queued messages to controllers and the ``message`` channel (done before every step)."""
        while self._outbox:
            outbox, self._outbox = self._outbox, []
            for msg in outbox:
                self.dispatch.message(msg)
                self.events.emit("message", msg)

    # ------------------------------------------------------------------ contacts
    def contact_triples(self) -> frozenset[tuple[str, str, str]]:
        """Current contacts as ``(entity, own part, other entity)``, both directions, the floor (``"ground"``)
        and wheels included."""
        return self._contacts.triples(self.step_count)

    def rolling_parts(self, robot: str) -> frozenset[str]:
        """Wheels and casters of ``robot`` (see ``sigcore.sim.contacts``): their floor contacts are no events."""
        return self._contacts.rolling_parts(robot)

    def _collisions(self) -> None:
        """Deliver the contact episodes that start at this step (``sigcore.sim.contacts``) to controllers and
        the ``collision`` channel."""
        for entity, part, other in self._contacts.events(self.step_count):
            event = CollisionEvent(entity, part, other, self.time)
            self.dispatch.collision(event)
            self.events.emit("collision", event)

    # ------------------------------------------------------------------ stepping
    def _contain(self, subscription: Subscription, exc: BaseException) -> bool:
        """A subscriber raised ``exc`` (``sigcore.sim.events``): disable the feature that owns it and return True, or
        False if no feature does (the hub re-raises: the core's, a transport's or a library user's error ends the
        run, with the error in its report)."""
        owner = subscription.owner
        if not isinstance(owner, FeatureOwner) or owner.name not in self.features:
            return False
        where = self._hooks.get(subscription) or f"{subscription.channel} observer"
        self.disable_feature(owner.name, where, exc)
        return True

    def disable_feature(self, feature: str, where: str, exc: BaseException) -> FeatureFailure:
        """Disable ``feature`` because ``where`` (``step observer``, ``reset``...) raised ``exc``: everything it
        subscribed on the hub is detached (not called again, even by a delivery in progress; its ``reset`` and
        ``entities_changed`` included), its viewer services removed; its ``summary``, ``report`` and ``outcome``
        are still asked at the end. Logged in one line.

        Returns:
            The failure, also in ``feature_guard.failures`` and the run's report.
        """
        guard = self.feature_guard
        failure = guard.fail(feature, where, self.time, exc)
        self.events.detach(FeatureOwner(feature))
        for service in [name for name, owner in guard.services.items() if owner == feature]:
            self.services.pop(service, None)
        return failure

    def start(self) -> None:
        """Start a run: call every ``on_init`` not called yet, then every ``on_action`` due now, then fire
        ``sigcore_simulation_started``. The first :meth:`step` calls it; idempotent until :meth:`stop`, after which
        it starts the next run (``on_init`` is never called twice)."""
        if self._started:
            return
        self._started = True
        self.dispatch.init(self.time)
        self.dispatch.actions(self.step_count, self.time)
        plugins.notify("sigcore_simulation_started", simulation=self)

    def stop(self) -> None:
        """End the run: fire ``sigcore_simulation_stopped`` (once; idempotent, and nothing before the run started).
        :func:`sigcore.sim.run` calls it at the end however the run ends; a library user who steps the simulation
        calls it when done. A later :meth:`step` or :meth:`start` starts a new run."""
        if not self._started:
            return
        self._started = False
        self.cameras.settle()
        plugins.notify("sigcore_simulation_stopped", simulation=self)

    def step(self, n: int = 1) -> None:
        """Advance ``n`` fixed steps: messages, forces, physics, contacts, controllers, sensors, the ``step`` channel.

        Raises:
            ApiError: no world is loaded (:meth:`unload_world`).
        """
        if not self.loaded:
            raise ApiError("no world is loaded: nothing to step; load one first (load_world)")
        if not self._started:
            self.start()
        backend = self.backend
        dispatch = self.dispatch
        cameras = self.cameras
        events = self.events
        for _ in range(n):
            if self._outbox:
                self.deliver_messages()
            if self._wrench:
                for (entity, part), (force, torque) in self._wrench.items():
                    backend.apply_wrench(entity, part, force, torque)
                self._wrench.clear()
            backend.step()
            self.step_count += 1
            if dispatch.collision_listeners or events.wanted("collision"):
                self._collisions()
            if dispatch.has_actions:
                dispatch.actions(self.step_count, self.time)
            for lidar in self.lidars:
                if self.step_count % lidar.period_steps == 0:
                    events.emit("scan", lidar.scan(backend, self.time))
            if cameras.every and (self.step_count % cameras.every == 0 or cameras.in_flight):
                cameras.capture(self.step_count)
            for odo in self.odometry.values():
                odo.update(backend, self.step_count * self.dt)
            events.emit("step", self)

    def reset(self, despawn: bool = True) -> None:
        """Restore the world's initial state; time goes on forward. Grasps, forces and queued messages are
        dropped, modes return to the world file's.

        Args:
            despawn: Also delete every entity spawned while running and bring back the world file's entities that
                were deleted (at their world-file pose, with new controllers), as simulation_interfaces' full
                reset does; False: only restore states (spawned entities go back to their state as spawned).
        """
        self.inputs.note("reset", despawn=despawn)
        self.cameras.settle()
        if despawn:
            if self.spawned:
                self.delete(list(self.spawned))
            missing = [e for e in self._initial_world.entities if e.name not in self.entity_names]
            if missing:
                self.add_entities(missing)
                for model in missing:
                    self.spawned.pop(model.name, None)
        self.backend.reset()
        self.grasps.clear()
        self.owners.clear()
        self._wrench.clear()
        self._outbox.clear()
        self._modes.reset()
        self.info.reset()
        self._contacts.reset()
        for odo in self.odometry.values():
            odo.reset()
        for drive in self._drives.values():
            drive.reset()
        self.events.emit("reset", Reset(despawn))

    def poses(self) -> dict[str, tuple[Array, Array]]:
        """Main-part pose of every entity (used to compare runs)."""
        return {name: self.backend.get_pose(name) for name in self.entity_names}

    def enable_odometry(self, robot: str, noise: float = 0.0) -> WheelOdometry:
        """Start integrating ``robot``'s wheel odometry every step (idempotent; costs about 2 µs per step)."""
        if robot not in self.odometry:
            odo = WheelOdometry(robot, self.drive(robot), self.backend, self.dt, noise, self.world.seed)
            self.odometry[robot] = odo
        return self.odometry[robot]

    def api_entries(self) -> list[ApiEntry]:
        """The core API table plus the entries of this world's features (what transports expose)."""
        entries = list(api_table())
        for feature_entries in self._feature_entries.values():
            entries.extend(feature_entries)
        return entries

    def summary(self) -> dict[str, Any]:
        """What each feature reports at the end of a run (a feature whose ``summary`` raises is disabled and left
        out)."""
        summaries = {}
        for name, feature in self.features.items():
            try:
                summaries[name] = feature.summary()
            except USER_ERRORS as e:
                self.disable_feature(name, "summary", e)
        return summaries

    def results(self) -> dict[str, Any]:
        """What each feature gives a program at the end of a run (``Feature.results``; one that raises is disabled
        and left out)."""
        results = {}
        for name, feature in self.features.items():
            try:
                results[name] = feature.results()
            except USER_ERRORS as e:
                self.disable_feature(name, "results", e)
        return results

    def report_lines(self) -> list[str]:
        """The features' report lines (``Feature.report``), in world order; one whose ``report`` raises is disabled
        and left out."""
        lines: list[str] = []
        for name, feature in self.features.items():
            try:
                lines.extend(str(line) for line in feature.report())
            except USER_ERRORS as e:
                self.disable_feature(name, "report", e)
        return lines

    def outcome(self) -> bool | None:
        """The world's verdict from the features' ``outcome``: False if any says False, or raises (no verdict can
        be trusted then; the feature is disabled); else True if any says True; else None."""
        verdicts = []
        for name, feature in self.features.items():
            try:
                verdicts.append(feature.outcome())
            except USER_ERRORS as e:
                self.disable_feature(name, "outcome", e)
                verdicts.append(False)
        return False if False in verdicts else True if True in verdicts else None
