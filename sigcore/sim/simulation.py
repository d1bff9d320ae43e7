"""The simulation: one world, one backend, one controller per agent, a fixed-step clock.

:class:`Simulation` is a facade over named parts, each the one owner of its state: :attr:`~Simulation.entities`
(``sigcore.sim.population``), :attr:`~Simulation.features` (``sigcore.sim.features``), :attr:`~Simulation.worlds`
(``sigcore.sim.worlds``), :attr:`~Simulation.control` (``sigcore.sim.control``), :attr:`~Simulation.events`
(``sigcore.sim.events``), :attr:`~Simulation.publications`, :attr:`~Simulation.inputs`, :attr:`~Simulation.frames`,
:attr:`~Simulation.cameras` and :attr:`~Simulation.scene`; the agents' publications are ``sigcore.sim.agent_topics``.
It keeps the clock, the step loop, wrenches and messages for the next step, and the reset.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence

import numpy as np

from .. import plugins
from ..agent.events import CollisionEvent, Message
from ..agent.exceptions import ApiError
from ..agent.handle import SimObj
from ..agent.robot import RobotObj
from ..api.table import ApiEntry
from ..backend import Array, Backend
from ..publish import Publications
from ..scene import Scene
from ..text import quote
from ..world.models import Entity, Human, Robot, World
from .agent_topics import AgentTopics
from .batching import free_steps
from .camera import Cameras
from .control import RunControl
from .events import Events, Reset, Subscriber, Subscription
from .features import FeatureHost, FeatureOwner
from .frames import Frames
from .inputs import Inputs
from .population import Entities
from .worlds import Worlds

log = logging.getLogger("sigcore")


class Simulation:
    """A running world.

    Args:
        world: The validated world.
        backend: A registered backend name (default ``"mujoco"``) or a backend instance.
        controllers: Controllers to attach instead of (or in addition to) the world file's, by agent name:
            a registered name or ``package.module:Class`` (e.g. ``{"robot_000": "cleanup.robot"}``).

    Raises:
        WorldError: a controller or feature named in the world cannot be created (located in the file).
        sigcore.errors.PluginError: the backend is not registered.
    """

    def __init__(self, world: World, backend: str | Backend = "mujoco",
                 controllers: Mapping[str, str] | None = None) -> None:
        # what lasts from one world to the next (worlds.load): the run's control, the event hub (what transports and
        # library users subscribed), the publication contract and its sinks, the clock of the whole process
        backend_class: type[Backend] = plugins.get_backend(backend) if isinstance(backend, str) else type(backend)
        self._events = Events(self._contain, self._owner_of)
        self._control = RunControl(loaded=lambda: self._worlds.loaded, reset=lambda despawn: self.reset(despawn),
                                   on_change=lambda change: self._events.emit("control", change),
                                   step_count=lambda: self._step_count)
        self._worlds = Worlds(self, backend_class, world, controllers or {}, self._setup, self._discard,
                              self._world_started)
        self._inputs = Inputs(self)
        self._sources_attached = False  # a publication sink has connected: the agents' sources are attached
        self._publications = Publications(lambda: self._step_count * self._dt_ns, self._attach_sources)
        self._started = False  # between start() and stop()
        self._setup(world, backend if isinstance(backend, Backend) else backend_class(), controllers or {}, True)

    def _setup(self, world: World, backend: Backend, controllers: Mapping[str, str], notify: bool) -> None:
        """Build everything that belongs to ``world`` (the constructor, and ``worlds.load`` after the old world
        was torn down); ``notify``: fire ``sigcore_world_loaded`` (not for the empty world of ``worlds.unload``)."""
        self._dt = world.timestep
        self._dt_ns = round(self._dt * 1e9)
        self._backend = backend
        backend.build(world)
        self._step_count = 0
        self._wrench: dict[tuple[str, str | None], list[Array]] = {}
        self._outbox: list[Message] = []
        self._entities = Entities(self, world, self._added, self._removed, lambda: self._started)
        self._frames = Frames(self)
        self._cameras = Cameras(self)
        for robot in world.agents:
            if isinstance(robot, Robot) and robot.cameras:
                self._cameras.add(robot.name, robot.cameras)
        self._scene = Scene(world, backend, self._frames.name, lambda scene: self._events.emit("scene", scene))
        self._features = FeatureHost(self)
        self._topics = AgentTopics(self, lambda: self._sources_attached)
        self._entities.attach_controllers(controllers)
        self._features.create()
        self._topics.declare()
        if notify:
            plugins.notify("sigcore_world_loaded", world=world)

    def _discard(self) -> None:
        """Drop everything of the current world; what lasts across worlds (control, what transports and library
        users subscribed, the publication sinks) stays."""
        for publication in self._publications.declared:
            self._publications.withdraw(publication.topic)
        self._features.detach_all()
        self._entities.people.close()
        self._topics.close()
        self._cameras.close()
        self._backend.close()

    def _world_started(self) -> None:
        """A world was just set up while the process runs: its controllers' ``on_init`` (and first ``on_action``)
        now if the run has started."""
        if self._started:
            self._entities.controllers.init(self.time)
            self._entities.controllers.actions(self._step_count, self.time)

    # ------------------------------------------------------------------ the parts (read-only)
    @property
    def world(self) -> World:
        """The running world as it is now (entities spawned or deleted while running included)."""
        return self._entities.world

    @property
    def dt(self) -> float:
        """The timestep [s]."""
        return self._dt

    @property
    def backend(self) -> Backend:
        """The physics backend of the running world."""
        return self._backend

    @property
    def step_count(self) -> int:
        """Steps taken in the running world."""
        return self._step_count

    @property
    def time(self) -> float:
        """Simulation time [s]: steps taken times the timestep (a reset does not move it back)."""
        return self._step_count * self._dt

    @property
    def events(self) -> Events:
        """The event hub (``sigcore.sim.events``): step, collision, message, scan, camera, entities, scene, world,
        reset, input and control; ``sim.events.subscribe(channel, fn)``."""
        return self._events

    @property
    def control(self) -> RunControl:
        """The run's state and its verbs (play, pause, step, request_reset, set_pace, stop; ``sigcore.sim.control``),
        which every client calls."""
        return self._control

    @property
    def entities(self) -> Entities:
        """The entities by name, their handles and per-entity state; spawn, add, delete (``sigcore.sim.population``)."""
        return self._entities

    @property
    def features(self) -> FeatureHost:
        """The world's features by name, their services and failures (``sigcore.sim.features``)."""
        return self._features

    @property
    def worlds(self) -> Worlds:
        """Load, unload and list worlds; the time of every world so far (``sigcore.sim.worlds``)."""
        return self._worlds

    @property
    def publications(self) -> Publications:
        """The publication contract (``sigcore.publish``) that transports, viewers and recorders are sinks of."""
        return self._publications

    @property
    def inputs(self) -> Inputs:
        """The core's verbs for commands from outside, logged for recordings and replays (``sigcore.sim.inputs``)."""
        return self._inputs

    @property
    def frames(self) -> Frames:
        """The TF tree (``sigcore.sim.frames``)."""
        return self._frames

    @property
    def cameras(self) -> Cameras:
        """Every ``<camera>`` of the robots, rendered off the simulation thread (``sigcore.sim.camera``)."""
        return self._cameras

    @property
    def scene(self) -> Scene:
        """Every entity's visual geometry and bounds (``sigcore.scene``); ``robot_description`` and
        ``/sigcore/scene`` are published from it."""
        return self._scene

    def stamp_ns(self) -> int:
        """Simulation time [ns], exact (what publications are stamped with)."""
        return self._step_count * self._dt_ns

    def agent(self, name: str) -> SimObj:
        """Handle of an agent; ``ApiError`` listing valid names if there is none (``entities.agent``)."""
        return self._entities.agent(name)

    def robot(self, name: str) -> RobotObj:
        """Handle of a robot; ``ApiError`` listing the robots otherwise (``entities.robot``)."""
        return self._entities.robot(name)

    def api_entries(self) -> list[ApiEntry]:
        """The core API table plus the entries of this world's features (what transports expose)."""
        return self._features.api_entries()

    # ------------------------------------------------------------------ the parts that learn of entities
    def _added(self, models: Sequence[Entity]) -> None:
        namespace = self._entities.namespace
        self._frames.add([(m.name, m.kind) for m in models])
        for model in models:
            if isinstance(model, Robot) and model.cameras:
                self._cameras.add(model.name, model.cameras, namespace(model.name))
        self._scene.add(self.world, models, self._frames.name)
        self._topics.add(m.name for m in models if isinstance(m, Robot | Human))
        self._topics.declare([m.name for m in models])

    def _removed(self, names: Sequence[str]) -> None:
        self._cameras.remove(names)
        self._frames.remove(names)
        self._scene.remove(names)
        for name in names:
            self._topics.remove(name)
        gone = set(names)
        self._wrench = {k: v for k, v in self._wrench.items() if k[0] not in gone}
        self._outbox = [m for m in self._outbox if m.to not in gone]

    def _attach_sources(self) -> None:
        """The first publication sink connected: attach the sources of the agents' publications."""
        self._sources_attached = True
        self._topics.attach()

    def _contain(self, subscription: Subscription, exc: BaseException) -> bool:
        """A subscriber raised: the feature that owns it is disabled (``FeatureHost.contain``)."""
        return self._features.contain(subscription, exc)

    def _owner_of(self, fn: Subscriber) -> FeatureOwner | None:
        features = getattr(self, "_features", None)
        return features.owner_of(fn) if features is not None else None

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
        if to not in self._entities:
            raise ApiError(f"no agent {quote(to)} to send to; agents: {', '.join(self._entities)}")
        if not isinstance(text, str):
            raise ApiError(f"message text must be a string, got {type(text).__name__}")
        self._outbox.append(Message(sender, to, text, self.time))

    def broadcast_msg(self, sender: str, text: str) -> None:
        """Queue ``text`` for every agent except ``sender``."""
        for name in self._entities:
            if name != sender:
                self.send_msg(sender, name, text)

    def deliver_messages(self) -> None:
        """Deliver queued messages to controllers and the ``message`` channel (done before every step)."""
        while self._outbox:
            outbox, self._outbox = self._outbox, []
            for msg in outbox:
                self._entities.controllers.message(msg)
                self._events.emit("message", msg)

    def contact_triples(self) -> frozenset[tuple[str, str, str]]:
        """Current contacts as ``(entity, own part, other entity)``, both directions, the floor (``"ground"``)
        and wheels included."""
        return self._entities.contacts.triples(self._step_count)

    # ------------------------------------------------------------------ the run
    def start(self) -> None:
        """Start a run: call every ``on_init`` not called yet, then every ``on_action`` due now, then fire
        ``sigcore_simulation_started``. The first :meth:`step` calls it; idempotent until :meth:`stop`, after which
        it starts the next run (``on_init`` is never called twice)."""
        if self._started:
            return
        self._started = True
        self._world_started()
        plugins.notify("sigcore_simulation_started", simulation=self)

    def stop(self) -> None:
        """End the run: fire ``sigcore_simulation_stopped`` (once; idempotent, and nothing before the run started).
        :func:`sigcore.sim.run` calls it at the end however the run ends; a library user who steps the simulation
        calls it when done. A later :meth:`step` or :meth:`start` starts a new run."""
        if not self._started:
            return
        self._started = False
        self._cameras.settle()
        plugins.notify("sigcore_simulation_stopped", simulation=self)

    def step(self, n: int = 1, *, until_stop: bool = False) -> None:
        """Advance ``n`` fixed steps: messages, forces, physics, contacts, controllers, sensors, the ``step`` channel.

        Steps after which nothing is due are taken by the backend in one call (:mod:`sigcore.sim.batching`); the
        results are the same as ``n`` single steps. ``until_stop``: also end after the step at which the run control
        was asked to stop (the run loop's batches).

        Raises:
            ApiError: no world is loaded (``worlds.unload``).
        """
        if not self._worlds.loaded:
            raise ApiError("no world is loaded: nothing to step; load one first (load_world)")
        if not self._started:
            self.start()
        backend = self._backend
        entities = self._entities
        dispatch = entities.controllers
        listeners = dispatch.collision_listeners
        contact_events = entities.contacts.events
        cameras = self._cameras
        events = self._events
        wanted, emit = events.wanted, events.emit
        odometry = entities.odometry
        dt = self._dt
        control = self._control
        batching = n > 1 and backend.batches
        while n > 0 and not (until_stop and (control.stopping or self._backend is not backend)):
            if self._outbox:
                self.deliver_messages()
            if self._wrench:
                self._apply_wrenches()
            track = bool(listeners) or wanted("collision")
            free = free_steps(entities, cameras, events, self._step_count, n) if batching and n > 1 else 1
            if free > 1:
                taken = backend.step_batch(free, track)
            else:
                backend.step()
                taken = 1
            n -= taken
            self._step_count = step = self._step_count + taken
            if track:
                for entity, part, other in contact_events(step):
                    event = CollisionEvent(entity, part, other, step * dt)
                    dispatch.collision(event)
                    emit("collision", event)
            if dispatch.has_actions:
                dispatch.actions(step, step * dt)
            for lidar in entities.lidars:
                if not step % lidar.period_steps:
                    emit("scan", lidar.scan(backend, step * dt))
            if cameras.every and (step % cameras.every == 0 or cameras.in_flight):
                cameras.capture(step)
            if odometry:
                for odo in odometry.values():
                    odo.update(backend, step * dt)
            events.emit_step(self, step)

    def _apply_wrenches(self) -> None:
        """Apply the forces and torques queued since the last step (they last one step)."""
        for (entity, part), (force, torque) in self._wrench.items():
            self._backend.apply_wrench(entity, part, force, torque)
        self._wrench.clear()

    def reset(self, despawn: bool = True) -> None:
        """Restore the world's initial state; time goes on forward. Grasps, forces and queued messages are
        dropped, modes return to the world file's.

        Args:
            despawn: Also delete every entity spawned while running and bring back the world file's entities that
                were deleted (at their world-file pose, with new controllers), as simulation_interfaces' full
                reset does; False: only restore states (spawned entities go back to their state as spawned).
        """
        self._inputs.note("reset", despawn=despawn)
        self._cameras.settle()
        if despawn:
            self._entities.restore()
        self._backend.reset()
        self._wrench.clear()
        self._outbox.clear()
        self._entities.reset()
        self._events.emit("reset", Reset(despawn))

    def poses(self) -> dict[str, tuple[Array, Array]]:
        """Main-part pose of every entity (used to compare runs)."""
        return {name: self._backend.get_pose(name) for name in self._entities.names}

