"""The simulation: one world, one backend, one controller per agent, a fixed-step clock."""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

import numpy as np

from .. import plugins
from ..agent.controller import Controller, resolve_controller
from ..agent.events import CollisionEvent, Message
from ..agent.exceptions import ApiError, ControllerError
from ..agent.handle import SimObj
from ..agent.robot import RobotObj
from ..api.table import ApiEntry, api_table
from ..backend import Array, Backend
from ..feature import Feature
from ..world.exceptions import WorldError, WorldIssue
from ..world.models import Drive, Human, Object, Robot, World
from ..world.urdf import UrdfModel, read_urdf
from .control import RunControl
from .dispatch import Dispatcher
from .lidar import LidarSensor, Scan
from .odometry import WheelOdometry

log = logging.getLogger("sigcore")

StepObserver = Callable[["Simulation"], None]


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
        self.world = world
        self.dt = world.timestep
        self.backend: Backend = plugins.get_backend(backend)() if isinstance(backend, str) else backend
        self.backend.build(world)
        self.step_count = 0
        self.control = RunControl()
        self._models = {a.name: a for a in world.agents}
        self.entity_names: list[str] = [e.name for e in world.entities]
        self._urdfs: dict[str, UrdfModel] = {
            r.name: read_urdf(world.resolve(r.urdf)) for r in world.agents if isinstance(r, Robot)
        }
        self.graspable: list[str] = [o.name for o in world.agents if isinstance(o, Object) and o.graspable]
        self.grasps: dict[tuple[str, str], str] = {}
        self.held_by: dict[str, tuple[str, str]] = {}
        self.owners: dict[tuple[str, str], str] = {}
        self.services: dict[str, Callable[[str, str], None]] = {}
        self.connections: dict[str, set[str]] = {}
        self._modes = {e.name: self._initial_modes(e) for e in world.entities}
        self._wrench: dict[tuple[str, str | None], list[Array]] = {}
        self._outbox: list[Message] = []
        self._contacts_step = -1
        self._triples: frozenset[tuple[str, str, str]] = frozenset()
        self._pairs: frozenset[tuple[int, int]] = frozenset()
        self.agents: dict[str, SimObj] = {
            a.name: (RobotObj if isinstance(a, Robot) else SimObj)(self, a.name, a.kind) for a in world.agents
        }
        self.dispatch = Dispatcher(self.dt)
        self.collision_observers: list[Callable[[CollisionEvent], None]] = []
        self.message_observers: list[Callable[[Message], None]] = []
        self.scan_observers: list[Callable[[Scan], None]] = []
        self._step_observers: list[StepObserver] = []
        self.lidars: list[LidarSensor] = [
            LidarSensor(r.name, lidar, self.dt, world.seed + i)
            for r in world.agents if isinstance(r, Robot) for i, lidar in enumerate(r.lidars)
        ]
        self.odometry: dict[str, WheelOdometry] = {}
        self._attach_controllers(controllers or {})
        self.features: dict[str, Feature] = {}
        self._create_features()
        self._started = False

    # ------------------------------------------------------------------ construction
    @staticmethod
    def _initial_modes(entity: Robot | Object | Human) -> dict[str, bool]:
        static = getattr(entity, "static", False)
        return {"gravity": True, "dynamics": not static, "collision": True}

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
                issues.append(self._issue(agent.name, "controller", str(e)))
                continue
            except Exception as e:
                issues.append(self._issue(agent.name, "controller",
                                          f"creating controller '{spec}' raised {type(e).__name__}: {e}"))
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
        issues = []
        for cfg in self.world.plugins:
            try:
                cls = plugins.get_feature(cfg.name)
            except plugins.PluginError as e:
                issues.append(self._issue("", "name", str(e), cfg.line))
                continue
            try:
                self.features[cfg.name] = cls(self, dict(cfg.config))
            except (ValueError, KeyError, TypeError) as e:
                issues.append(self._issue("", None, f"plugin '{cfg.name}': {e}", cfg.line))
        if issues:
            raise WorldError(issues)

    # ------------------------------------------------------------------ lookups used by handles and the API
    @property
    def time(self) -> float:
        """Simulation time [s]: steps taken times the timestep (a reset does not move it back)."""
        return self.step_count * self.dt

    def agent(self, name: str) -> SimObj:
        """Handle of an agent; ``ApiError`` listing valid names if there is none."""
        try:
            return self.agents[name]
        except KeyError:
            raise ApiError(f"no agent '{name}'; agents: {', '.join(self.agents)}") from None

    def robot(self, name: str) -> RobotObj:
        """Handle of a robot; ``ApiError`` listing the robots otherwise."""
        handle = self.agent(name)
        if not isinstance(handle, RobotObj):
            robots = [n for n, h in self.agents.items() if isinstance(h, RobotObj)]
            raise ApiError(f"'{name}' is a {handle.kind}, not a robot; robots: {', '.join(robots) or 'none'}")
        return handle

    def robot_model(self, name: str) -> Robot:
        """The world model of robot ``name``."""
        model = self._models[name]
        assert isinstance(model, Robot)
        return model

    def urdf(self, robot: str) -> UrdfModel:
        """The URDF names of robot ``robot``."""
        return self._urdfs[robot]

    def drive(self, robot: str) -> Drive:
        """The differential drive of ``robot``; ``ApiError`` if it has none."""
        drive = self.robot_model(robot).drive
        if drive is None:
            raise ApiError(f"robot '{robot}' has no <drive> in the world file")
        return drive

    def wheels(self, robot: str) -> tuple[float, float]:
        """``(radius, separation)`` [m] of ``robot``'s drive."""
        d = self.drive(robot)
        return d.radius, d.separation

    def modes(self, entity: str) -> dict[str, bool]:
        """Current gravity/dynamics/collision modes of an entity."""
        return self._modes[entity]

    def set_mode(self, entity: str, mode: str, enabled: bool) -> None:
        """Switch ``gravity``, ``dynamics`` or ``collision`` for an entity."""
        setter = {"gravity": self.backend.set_gravity_mode, "dynamics": self.backend.set_dynamics_mode,
                  "collision": self.backend.set_collision_mode}[mode]
        setter(entity, enabled)
        self._modes[entity][mode] = enabled

    def register_service(self, name: str, handler: Callable[[str, str], None]) -> None:
        """Offer a viewer service (e.g. a referee): ``handler(sender, text)`` receives ``_send_msg_to_srv`` texts
        and raises ``ApiError`` to refuse one."""
        self.services[name] = handler

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
            raise ApiError(f"no agent '{to}' to send to; agents: {', '.join(self.agents)}")
        if not isinstance(text, str):
            raise ApiError(f"message text must be a string, got {type(text).__name__}")
        self._outbox.append(Message(sender, to, text, self.time))

    def broadcast_msg(self, sender: str, text: str) -> None:
        """Queue ``text`` for every agent except ``sender``."""
        for name in self.agents:
            if name != sender:
                self.send_msg(sender, name, text)

    def deliver_messages(self) -> None:
        """Deliver queued messages to controllers and observers (done before every step)."""
        while self._outbox:
            outbox, self._outbox = self._outbox, []
            for msg in outbox:
                self.dispatch.message(msg)
                for observer in self.message_observers:
                    observer(msg)

    # ------------------------------------------------------------------ contacts
    def contact_triples(self) -> frozenset[tuple[str, str, str]]:
        """Current contacts as ``(entity, own part, other entity)``, both directions."""
        if self._contacts_step != self.step_count:
            self._refresh_contacts()
        return self._triples

    def _refresh_contacts(self) -> None:
        self._contacts_step = self.step_count
        pairs = self.backend.contacts()
        if pairs == self._pairs:
            return
        self._pairs = pairs
        part_of = self.backend.part_of
        triples = set()
        for a, b in pairs:
            ea, pa = part_of(a)
            eb, pb = part_of(b)
            if ea != eb:
                triples.add((ea, pa, eb))
                triples.add((eb, pb, ea))
        self._triples = frozenset(triples)

    def _collisions(self) -> None:
        before = self._triples
        self._refresh_contacts()
        if self._triples is before:
            return
        for entity, part, other in sorted(self._triples - before):
            if entity not in self.agents:
                continue  # the ground
            event = CollisionEvent(entity, part, other, self.time)
            self.dispatch.collision(event)
            for observer in self.collision_observers:
                observer(event)

    # ------------------------------------------------------------------ stepping
    def add_step_observer(self, observer: StepObserver) -> None:
        """Call ``observer(sim)`` after every step (features and transports; keep it cheap)."""
        self._step_observers.append(observer)

    def start(self) -> None:
        """Call every ``on_init``, then every ``on_action`` due at time 0 (done by the first step if not called)."""
        if self._started:
            return
        self._started = True
        self.dispatch.init(self.time)
        self.dispatch.actions(self.step_count, self.time)
        plugins.notify("sigcore_simulation_started", simulation=self)

    def step(self, n: int = 1) -> None:
        """Advance ``n`` fixed steps: messages, forces, physics, contacts, controllers, sensors, observers."""
        if not self._started:
            self.start()
        backend = self.backend
        dispatch = self.dispatch
        for _ in range(n):
            if self._outbox:
                self.deliver_messages()
            if self._wrench:
                for (entity, part), (force, torque) in self._wrench.items():
                    backend.apply_wrench(entity, part, force, torque)
                self._wrench.clear()
            backend.step()
            self.step_count += 1
            if dispatch.collision_listeners or self.collision_observers:
                self._collisions()
            if dispatch._action:
                dispatch.actions(self.step_count, self.time)
            for lidar in self.lidars:
                if self.step_count % lidar.period_steps == 0:
                    scan = lidar.scan(backend, self.time)
                    for scan_observer in self.scan_observers:
                        scan_observer(scan)
            for odo in self.odometry.values():
                odo.update(backend, self.step_count * self.dt)
            for observer in self._step_observers:
                observer(self)

    def reset(self) -> None:
        """Restore the world's initial state; time goes on forward. Grasps, forces and queued messages are
        dropped, modes return to the world file's."""
        self.backend.reset()
        self.grasps.clear()
        self.held_by.clear()
        self._wrench.clear()
        self._outbox.clear()
        self._modes = {e.name: self._initial_modes(e) for e in self.world.entities}
        self._contacts_step = -1
        self._pairs = frozenset()
        self._triples = frozenset()
        for odo in self.odometry.values():
            odo.reset()
        for feature in self.features.values():
            feature.reset()

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
        for feature in self.features.values():
            entries.extend(feature.api_entries())
        return entries

    def summary(self) -> dict[str, Any]:
        """What each feature reports at the end of a run."""
        return {name: f.summary() for name, f in self.features.items()}
