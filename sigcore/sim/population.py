"""The entities of one world (``sim.entities``): who is there, with what, and how entities come and go.

:class:`Entities` is a read-only mapping ``name -> handle`` (``SimObj`` / ``RobotObj``) in world order, and the one
owner of the per-entity state that spawning and deleting change: models, URDFs, drives, lidars, wheel odometry,
namespaces, graspable objects, modes, information, grasps, owners, contacts, controllers and people's motion.
:meth:`Entities.spawn` resolves requests (``sigcore.world.resources``), :meth:`Entities.add` and
:meth:`Entities.delete` change every owner at once, then emit ``scene`` and ``entities`` on the event hub.
"""

from __future__ import annotations

import logging
import shutil
import tempfile
import weakref
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING

from .. import plugins
from ..agent.controller import Controller, resolve_controller
from ..agent.exceptions import ApiError, ControllerError
from ..agent.handle import SimObj
from ..agent.robot import RobotObj
from ..errors import BackendError
from ..geometry import quat_mul, quat_rotate
from ..isolation import USER_ERRORS, describe
from ..text import quote
from ..world.exceptions import SpawnRefusal, WorldError, WorldIssue
from ..world.models import AgentModel, Entity, Human, Object, Robot, Spawnable, World
from ..world.resources import SpawnRequest, build_model, check_pose, normalize_namespace, resource_element, unique_name
from ..world.urdf import UrdfModel
from .contacts import ContactTracker, rolling_parts
from .dispatch import Dispatcher
from .drive import DriveState
from .grasps import Grasps
from .info import EntityInfos
from .lidar import LidarSensor
from .modes import Mode, Modes
from .odometry import WheelOdometry
from .owners import Owners
from .people import People
from .spawn import EntityChange

if TYPE_CHECKING:
    from .simulation import Simulation

log = logging.getLogger("sigcore")


class Entities(Mapping[str, SimObj]):
    """The entities of the running world, by name: their handles, and everything kept per entity.

    Args:
        sim: The simulation (its backend, clock, event hub, and the parts that learn of added or removed entities).
        world: The world as loaded.
        added: Called with the models just added, after this part changed and before ``entities`` is emitted.
        removed: Called with the names just removed, likewise.
        started: Whether the run has started (a spawned entity's ``on_init`` is called at once then).
    """

    def __init__(self, sim: Simulation, world: World, added: Callable[[Sequence[Entity]], None],
                 removed: Callable[[Sequence[str]], None], started: Callable[[], bool]) -> None:
        self._sim = sim
        self._added, self._removed, self._started = added, removed, started
        self.world = world
        """The world as it is now (spawned entities included, deleted ones gone)."""
        self._initial = world
        dt = world.timestep
        self._models = {a.name: a for a in world.agents}
        self._names = [e.name for e in world.entities]
        self._handles: dict[str, SimObj] = {a.name: self._handle(a) for a in world.agents}
        self._urdfs: dict[str, UrdfModel] = {a.name: world.urdf(a.name).model for a in world.agents
                                             if isinstance(a, Robot | Human)}
        self._drives = {r.name: DriveState(r.name, r.drive) for r in self._robots(world.agents)
                        if r.drive is not None}
        self._graspable = [o.name for o in world.agents if isinstance(o, Object) and o.graspable]
        self._spawned: dict[str, str] = {}
        self.lidars = tuple(LidarSensor(r.name, lidar, dt, world.seed + i)
                            for r in self._robots(world.agents) for i, lidar in enumerate(r.lidars))
        """Every lidar of the robots (``<lidar>``), in world order (a new tuple when robots come or go)."""
        self._odometry: dict[str, WheelOdometry] = {}
        self.odometry = MappingProxyType(self._odometry)
        """The robots whose wheel odometry is integrated (:meth:`enable_odometry`) -> their odometry (a read-only
        view)."""
        self._modes = Modes(sim.backend, world.entities)
        self.contacts = ContactTracker(sim.backend, list(self._models),
                                       {r.name: rolling_parts(r, self._urdfs[r.name]) for r in self._robots(
                                           world.agents)}, dt)
        """The contact state: triples and the contact episodes that start at a step (``sigcore.sim.contacts``)."""
        self.info = EntityInfos(world.entities)
        """Category, description and tags of every entity (``set_entity_info`` changes them, a reset restores)."""
        self.grasps = Grasps()
        """Who holds what (changed by ``RobotObj.grasp`` / ``release``; read by anyone)."""
        self.owners = Owners()
        """Who owns which part (``SimObj.set_owner``)."""
        self.controllers = Dispatcher(dt)
        """The agents' controllers and their callbacks (``sigcore.sim.dispatch``)."""
        self.people = People(sim, world, lambda: self.world)
        """What moves each person (``sigcore.sim.people``: walking by velocity, walking a path)."""
        self._spawn_dir: Path | None = None

    def _handle(self, model: AgentModel) -> SimObj:
        return (RobotObj if isinstance(model, Robot) else SimObj)(self._sim, model.name, model.kind)

    @staticmethod
    def _robots(agents: Sequence[AgentModel]) -> list[Robot]:
        return [a for a in agents if isinstance(a, Robot)]

    # ------------------------------------------------------------------ the mapping and lookups
    def __getitem__(self, name: str) -> SimObj:
        return self._handles[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._handles)

    def __len__(self) -> int:
        return len(self._handles)

    @property
    def names(self) -> tuple[str, ...]:
        """Every entity's name, in world order (spawned ones last)."""
        return tuple(self._names)

    @property
    def graspable(self) -> tuple[str, ...]:
        """The objects a robot may grasp."""
        return tuple(self._graspable)

    @property
    def spawned(self) -> Mapping[str, str]:
        """Entities added while running -> their namespace (``""`` or ``/ns``); a copy."""
        return dict(self._spawned)

    def namespace(self, agent: str) -> str:
        """The ROS namespace of ``agent``'s endpoints: ``""`` for the world file's, ``/ns`` for one spawned with
        a namespace."""
        return self._spawned.get(agent, "")

    def agent(self, name: str) -> SimObj:
        """Handle of an agent; ``ApiError`` listing valid names if there is none."""
        try:
            return self._handles[name]
        except KeyError:
            raise ApiError(f"no agent {quote(name)}; agents: {', '.join(self._handles)}") from None

    def robot(self, name: str) -> RobotObj:
        """Handle of a robot; ``ApiError`` listing the robots otherwise."""
        handle = self.agent(name)
        if not isinstance(handle, RobotObj):
            robots = [n for n, h in self._handles.items() if isinstance(h, RobotObj)]
            article = "an" if handle.kind[0] in "aeiou" else "a"
            raise ApiError(f"'{name}' is {article} {handle.kind}, not a robot; robots: {', '.join(robots) or 'none'}")
        return handle

    def robot_model(self, name: str) -> Robot:
        """The world model of robot ``name``."""
        model = self._models[name]
        assert isinstance(model, Robot)
        return model

    def urdf(self, robot: str) -> UrdfModel:
        """The URDF names of robot or person ``robot`` (of the world's shared document, ``World.urdf``; a person's is
        generated)."""
        return self._urdfs[robot]

    def drive(self, robot: str) -> DriveState:
        """The differential drive of ``robot`` as it is now (geometry set by ``_setWheel``; the world file's
        ``<drive>`` is its ``model``); ``ApiError`` if it has none."""
        state = self._drives.get(robot)
        if state is None:
            raise ApiError(f"robot '{robot}' has no <drive> in the world file")
        return state

    def modes(self, entity: str) -> dict[str, bool]:
        """Current gravity/dynamics/collision modes of an entity (a copy)."""
        return self._modes.of(entity)

    def mode(self, entity: str, mode: Mode) -> bool:
        """Whether ``mode`` (``gravity``, ``dynamics``, ``collision``) is on for ``entity``."""
        return self._modes.get(entity, mode)

    def set_mode(self, entity: str, mode: Mode, enabled: bool) -> None:
        """Switch ``gravity``, ``dynamics`` or ``collision`` for an entity."""
        self._modes.set(entity, mode, enabled)

    def enable_odometry(self, robot: str, noise: float = 0.0) -> WheelOdometry:
        """Start integrating ``robot``'s wheel odometry every step (idempotent; costs about 2 µs per step)."""
        if robot not in self._odometry:
            self._odometry[robot] = WheelOdometry(robot, self.drive(robot), self._sim.backend, self._sim.dt, noise,
                                                  self.world.seed)
        return self._odometry[robot]

    # ------------------------------------------------------------------ contacts
    def rolling_parts(self, robot: str) -> frozenset[str]:
        """Wheels and casters of ``robot`` (see ``sigcore.sim.contacts``): their floor contacts are no events."""
        return self.contacts.rolling_parts(robot)

    def _refresh_contacts(self) -> None:
        robots = self._robots(self.world.agents)
        self.contacts.set_agents([a.name for a in self.world.agents],
                                  {r.name: rolling_parts(r, self._urdfs[r.name]) for r in robots})

    # ------------------------------------------------------------------ controllers
    def attach_controllers(self, overrides: Mapping[str, str]) -> None:
        """Create the world file's controllers (or those of ``overrides``, by agent name).

        Raises:
            ApiError: ``overrides`` names no agent.
            WorldError: a controller cannot be created (located at its attribute).
        """
        unknown = sorted(set(overrides) - set(self._handles))
        if unknown:
            raise ApiError(f"no agent {', '.join(repr(u) for u in unknown)} to attach a controller to; agents: "
                           f"{', '.join(self._handles)}")
        registered = plugins.controllers()
        issues = []
        for agent in self.world.agents:
            spec = overrides.get(agent.name, agent.controller)
            if spec is None:
                continue
            ln, col = self.world.location(agent.name, "controller")
            try:
                controller = resolve_controller(spec, registered)()
            except ControllerError as e:
                issues.append(WorldIssue(self.world.source, ln, col, agent.kind, "controller",
                                         f"agent '{agent.name}': {e}"))
                continue
            except USER_ERRORS as e:  # its constructor raised or called sys.exit
                detail = describe(e).partition(": ")[2]  # the message, or that sys.exit was called
                issues.append(WorldIssue(self.world.source, ln, col, agent.kind, "controller",
                                         f"controller '{spec}' of agent '{agent.name}' raised {type(e).__name__} "
                                         f"while being created: {detail}"))
                continue
            self.controllers.add(self._handles[agent.name], controller)
        if issues:
            raise WorldError(issues)

    def set_controller(self, agent: str, controller: Controller) -> None:
        """Attach a controller instance to an agent (before the first step)."""
        if self._started():
            raise ApiError("controllers are attached before the simulation starts")
        self.controllers.add(self.agent(agent), controller)

    # ------------------------------------------------------------------ run-time changes (sigcore.world.resources)
    def spawnables(self) -> list[Spawnable]:
        """What ``model://NAME`` may name (``sigcore.world.spawnables``)."""
        from ..world.spawnables import find_spawnables

        return find_spawnables(self.world, plugins.spawnables().values())

    def _spawnable(self, name: str) -> Spawnable:
        from ..world.spawnables import spawnable

        return spawnable(self.world, name, plugins.spawnables().values())

    def _taken(self) -> dict[str, str]:
        return {**self._sim.frames.taken(), **{a: f"agent '{a}'" for a in self._handles}}

    def spawn(self, requests: Sequence[SpawnRequest]) -> list[str | SpawnRefusal]:
        """Add entities while running (between steps): each request is resolved and validated like a world file's
        element; the valid ones are added in one backend call.

        Returns:
            Per request, the name the entity got, or the :class:`SpawnRefusal` saying why it was not added (a
            backend failure refuses every request of the call: nothing is added then).
        """
        if not self._sim.worlds.loaded:
            return [SpawnRefusal("OPERATION_FAILED", "no world is loaded to spawn into; load one first (load_world)")
                    for _ in requests]
        results: list[str | SpawnRefusal] = []
        models: list[Entity] = []
        namespaces: dict[str, str] = {}
        taken = self._taken()
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
                self.add(models, namespaces)
            except SpawnRefusal as refusal:
                results = [refusal if isinstance(r, str) else r for r in results]
        return results

    def _resolve(self, request: SpawnRequest, taken: dict[str, str]) -> tuple[Entity, str]:
        namespace = normalize_namespace(request.namespace)
        xyz, wxyz = check_pose(request.xyz, request.wxyz)
        frame = request.frame.strip()
        if frame not in ("", "world"):
            if frame not in self._names:
                raise SpawnRefusal("INVALID_POSE", f"pose frame '{frame[:80]}' is unknown; valid: 'world' (or empty) "
                                                   f"or an entity: {', '.join(self._names)}")
            pos, quat = self._sim.backend.get_pose(frame)
            xyz, wxyz = pos + quat_rotate(quat, xyz), quat_mul(quat, wxyz)
        if self._spawn_dir is None:  # URDF texts of requests, removed with the simulation
            self._spawn_dir = Path(tempfile.mkdtemp(prefix="sigcore-spawn-"))
            weakref.finalize(self, shutil.rmtree, self._spawn_dir, True)
        element, base, default = resource_element(request, self.world, self._spawn_dir, self._spawnable)
        wanted = request.name.strip() or str(element.get("name", "")).strip() or default
        name = unique_name(wanted, taken, request.allow_renaming)
        model = build_model(self.world, element, base, name, (xyz, wxyz), request.tags)
        return model, namespace

    def add(self, models: Sequence[Entity], namespaces: Mapping[str, str] | None = None) -> list[str]:
        """Add validated entity models while running (between steps), in one backend call: every owner of
        per-entity state learns of them, their controllers are created (``on_init`` called at once when the run
        has started), the ``entities`` channel is emitted (features, transports).

        Raises:
            SpawnRefusal: a name is taken or names a TF frame in use (NAME_NOT_UNIQUE), a controller cannot be
                created or a person cannot walk its <path> (RESOURCE_PARSE_ERROR), the backend failed
                (OPERATION_FAILED); nothing changed then.
        """
        namespaces = namespaces or {}
        taken = self._taken()
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
        why = self.people.refusal(models)
        if why is not None:
            raise SpawnRefusal("RESOURCE_PARSE_ERROR", why)
        world = self.world.with_agents(self.world.agents + tuple(models))
        try:
            self._sim.backend.add_entities(world, names)
        except BackendError as e:
            raise SpawnRefusal("OPERATION_FAILED", f"the backend could not add {', '.join(names)}: {e}") from None
        self.world = world
        lidars = list(self.lidars)
        for model in models:
            self._models[model.name] = model
            self._names.append(model.name)
            self._spawned[model.name] = namespaces.get(model.name, "")
            self._handles[model.name] = self._handle(model)
            if isinstance(model, Robot | Human):
                self._urdfs[model.name] = world.urdf(model.name).model
            if isinstance(model, Robot):
                if model.drive is not None:
                    self._drives[model.name] = DriveState(model.name, model.drive)
                lidars.extend(LidarSensor(model.name, lidar, world.timestep, world.seed + len(lidars) + i)
                              for i, lidar in enumerate(model.lidars))
            if isinstance(model, Object) and model.graspable:
                self._graspable.append(model.name)
        self.lidars = tuple(lidars)
        self.people.add(models)
        self.info.add(models)
        self._modes.add(models)
        self._refresh_contacts()
        self._added(models)
        for name, controller in controllers.items():
            self.controllers.add(self._handles[name], controller)
        if self._started():
            self.controllers.init(self._sim.time)
        log.info("spawned %s at t=%.3f s", ", ".join(f"{m.kind} '{m.name}'" for m in models), self._sim.time)
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
            if name not in self._names:
                raise SpawnRefusal("NOT_FOUND", f"no entity {quote(name)} to delete; entities: "
                                                f"{', '.join(self._names) or 'none'}")
            for cfg in self.world.plugins:
                if name in " ".join(cfg.config.values()).split():
                    raise SpawnRefusal("OPERATION_FAILED", f"'{name}' is named by <plugin name=\"{cfg.name}\"> "
                                                           "of the world file; it cannot be deleted while that "
                                                           "feature runs")
        gone = set(names)
        backend = self._sim.backend
        for robot, part, obj in self.grasps.items():
            if robot in gone or obj in gone:
                self.grasps.release(robot, part)
                backend.detach(robot, part, obj)
        world = self.world.with_agents(tuple(a for a in self.world.agents if a.name not in gone))
        try:
            backend.remove_entities(world, names)
        except BackendError as e:
            raise SpawnRefusal("OPERATION_FAILED", f"the backend could not remove {', '.join(names)}: {e}") from None
        self._removed(names)
        for name in names:
            self.controllers.remove(name)
            del self._handles[name]
            del self._models[name]
            self._names.remove(name)
            self._spawned.pop(name, None)
            self._urdfs.pop(name, None)
            self._drives.pop(name, None)
            self._odometry.pop(name, None)
            if name in self._graspable:
                self._graspable.remove(name)
        self.world = world
        self.lidars = tuple(lidar for lidar in self.lidars if lidar.robot not in gone)
        self.info.remove(names)
        self.people.remove(names)
        self._modes.remove(names)
        self.owners.forget(gone)
        self._refresh_contacts()
        log.info("deleted %s at t=%.3f s", ", ".join(repr(n) for n in names), self._sim.time)
        self._changed(EntityChange(removed=tuple(names)))

    def is_robot(self, name: str) -> bool:
        """Whether entity ``name`` is a robot."""
        return isinstance(self._models.get(name), Robot)

    def _changed(self, change: EntityChange) -> None:
        """Emit ``scene`` (the scene's version bumped), then ``entities`` (features' ``entities_changed``,
        transports)."""
        self._sim.scene.changed()
        self._sim.events.emit("entities", change)

    # ------------------------------------------------------------------ reset
    def restore(self) -> None:
        """Delete every entity spawned while running and bring back the world file's entities that were deleted (at
        their world-file pose, with new controllers)."""
        if self._spawned:
            self.delete(list(self._spawned))
        missing = [e for e in self._initial.entities if e.name not in self._names]
        if missing:
            self.add(missing)
            for model in missing:
                self._spawned.pop(model.name, None)

    def reset(self) -> None:
        """The per-entity state back to the world file's (after the backend's reset): no grasps or owners, modes and
        information as loaded, no contact episode, odometry and drives at their start, everyone standing."""
        self.grasps.clear()
        self.owners.clear()
        self._modes.reset()
        self.info.reset()
        self.contacts.reset()
        for odo in self._odometry.values():
            odo.reset()
        for drive in self._drives.values():
            drive.reset()
        self.people.reset()
