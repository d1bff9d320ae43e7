"""The ROS 2 transport: every agent's API, the idiomatic topics and simulation_interfaces over real rclpy.

Threads: a receiver thread waits in ``rcl_wait`` and queues incoming messages and requests; they are handled
on the simulation thread in :meth:`Ros2Transport.service`, between steps, so the simulation never blocks on ROS
and the same inputs at the same steps give the same results. Publishing happens in step observers, stamped with
the step's simulated time. The simulate_steps action has its own small node and executor thread.

Worlds come and go while running (``load_world``, ``unload_world``; the ``world`` event): the node, its context,
the receiver, the action node and the simulation_interfaces services stay; the agents' endpoints and the robots'
topics of the old world are destroyed and those of the new one created, with the settings the transport started
with (``sim_prefix``, QoS, ``sigros_agents``).
"""

from __future__ import annotations

import logging
import sys
import threading
import time
from typing import TYPE_CHECKING, Any

from sigcore.api.call import log_key
from sigcore.errors import TransportError
from sigcore.text import clip
from sigcore.transport import Endpoint, Transport, publication_endpoints

from .config import Ros2Config, config_for, selects_model, sigros_agents
from .logfilter import OncePerKind
from .rosargs import RosArgs, parse_ros_args, validate_settings

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation
    from sigcore.sim.spawn import EntityChange, WorldChange

log = logging.getLogger("sigcore.ros2")

SWITCH_INTERVAL = 0.0001
"""Python's thread switch interval while the transport runs [s] (the default 5 ms would delay requests)."""

PAUSED_CLOCK_PERIOD = 0.1
"""While paused, /clock repeats the current time this often [s of wall time], like other simulators do."""

FLUSH_TIMEOUT = 2.0
"""At the end, wait at most this long [s] for subscribers to acknowledge the last messages (e.g. a result)."""

READY_TOPIC = "/sigcore/ready"
"""Latched std_msgs/Bool, true once every endpoint exists (and false when the simulation stops)."""


class Ros2Transport(Transport):
    """Exposes a simulation over ROS 2 (selected with ``sigcore run --transport ros2``).

    Args:
        config: Settings; default: the world's ``<plugin name="ros2">`` attributes, else the defaults.
        node_name: Name of the main node.
    """

    name = "ros2"

    @classmethod
    def unavailable(cls) -> str | None:
        """Why rclpy cannot be imported (ROS 2 missing), or None."""
        try:
            import rclpy  # noqa: F401 - only whether it imports
        except Exception as e:  # ImportError, or a broken ROS 2 install raising while loading its libraries
            return f"rclpy cannot be imported ({type(e).__name__}: {e}); run scripts/setup.sh or source ROS 2 Jazzy"
        return None

    def __init__(self, config: Ros2Config | None = None, node_name: str = "sigcore") -> None:
        self._config = config
        self._node_name = node_name
        self._sim: Simulation | None = None
        self._context: Any = None
        self._filter = OncePerKind()
        self._idle_clock = 0.0
        self._args = RosArgs()
        self.endpoints: dict[str, str] = {}
        """Every endpoint that exists, name -> ROS type (after :meth:`start`; updated when entities come and go)."""
        self._fixed: dict[str, str] = {}  # the action and readiness topic (on their own, after the others)
        self._index: tuple[object, dict[str, Any]] = (None, {})  # world -> its agents' models by name

    # ------------------------------------------------------------------ Transport
    def configure(self, args: list[str]) -> None:
        """Take ``--ros-args``: remappings and ``--log-level`` for rcl (``--log-level`` also sets the Python
        ``sigcore`` loggers), ``-p NAME:=VALUE`` for the settings (:mod:`sigcore_ros2.rosargs`).

        Raises:
            TransportError: an argument is unknown or invalid (naming it and what is valid).
        """
        self._args = parse_ros_args(args)
        if self._args.log_level is not None:
            logging.getLogger("sigcore").setLevel(self._args.log_level)

    def settings(self, sim: Simulation) -> Ros2Config:
        """The settings for ``sim``: the constructor's, else the world's ``<plugin name="ros2">``, with the
        ``--ros-args -p`` parameters applied.

        Raises:
            TransportError: a parameter's value is invalid for this world (e.g. ``sigros_agents`` names no agent).
        """
        config = self._config or config_for(sim)
        params = {k: v for k, v in self._args.params.items() if k != "use_sim_time"}
        if params:
            config = validate_settings(params, config)
            why = sigros_agents(sim.world, config.sigros_agents)[1]
            if why is not None:
                raise TransportError(f"-p sigros_agents:={self._args.params.get('sigros_agents')}: {why}")
        return config

    def matched(self, topic: str) -> tuple[int, str]:
        """Matched subscriptions of a topic the transport publishes, or matched publishers of one it subscribes
        to (``topic`` as planned; remappings are applied).

        Raises:
            TransportError: before :meth:`start`, or ``topic`` is none of the transport's topics.
        """
        if self._context is None:
            raise TransportError("the ROS 2 transport has not started: no peers to count")
        node = self._node
        try:
            resolved = node.resolve_topic_name(topic)
        except Exception as e:  # rclpy's name errors
            raise TransportError(f"'{topic}' is not a valid topic name: {e}") from None
        pubs = [p for p in node.publishers if p.topic_name == resolved]
        subs = [s for s in node.subscriptions if s.topic_name == resolved]
        # the node's own endpoints match each other (its use_sim_time subscription to /clock): not counted
        if pubs:
            return max(p.get_subscription_count() for p in pubs) - len(subs), "subscriber"
        if subs:
            return max(s.get_publisher_count() for s in subs), "publisher"
        raise TransportError(f"'{topic}' ({resolved}) is none of the transport's topics")

    def plan(self, sim: Simulation) -> list[Endpoint]:
        """Every endpoint :meth:`start` creates for ``sim``, with who asked for it, without ROS: the agents'
        subscriptions and services, the declared publications, the idiomatic topics, simulation_interfaces,
        readiness (:meth:`describe` lists their names and types)."""
        from .sigros import SigRosEndpoints
        from .siminterfaces import SERVICES
        from .standard import StandardEndpoints

        config = self.settings(sim)
        agents = sigros_agents(sim.world, config.sigros_agents)[0]
        out: list[Endpoint] = []
        if config.sigros:
            out += [Endpoint(entry.name_for(agent), entry.ros_type,
                             "service" if entry.direction == "service" else "topic",
                             f"'{entry.suffix}' of {sim.entities[agent].kind} '{agent}'", agent, "name")
                    for entry, agent in SigRosEndpoints.plan(sim, agents)]
            out += [Endpoint(name, entry.ros_type, "service" if entry.direction == "service" else "topic",
                             f"the transport's shared '{entry.suffix}' (every agent, by the request's name)")
                    for entry, name in SigRosEndpoints.shared_plan(sim)]
        out += publication_endpoints(sim, agents=agents if config.sigros else False)
        if config.standard:
            out += StandardEndpoints.plan(sim)
        prefix = config.sim_prefix
        ros2 = "ros2" if sim.world.plugin("ros2") is not None else None
        attribute = "sim_prefix" if ros2 else None
        out += [Endpoint(f"{prefix}/{name}", f"simulation_interfaces/srv/{srv.__name__}", "service",
                         f"the transport's simulation_interfaces service '{name}'", plugin=ros2, attribute=attribute)
                for name, srv in SERVICES.items()]
        out.append(Endpoint(f"{prefix}/simulate_steps", "simulation_interfaces/action/SimulateSteps", "action",
                            "the transport's simulate_steps action", plugin=ros2, attribute=attribute))
        out.append(Endpoint(READY_TOPIC, "std_msgs/msg/Bool", "topic", "the transport's readiness topic"))
        return out

    def name_problem(self, name: str) -> str | None:
        """rclpy's own rule for a full topic or service name (the core's when rclpy cannot be imported)."""
        try:
            from rclpy.exceptions import InvalidTopicNameException
            from rclpy.validate_full_topic_name import validate_full_topic_name
        except ImportError:
            return super().name_problem(name)
        try:
            validate_full_topic_name(name)
        except InvalidTopicNameException as e:
            return str(e).splitlines()[0].removeprefix("Invalid topic name: ").rstrip(":")
        return None

    # ------------------------------------------------------------------ Transport
    def start(self, sim: Simulation) -> None:
        """Create the node and every endpoint, publish /clock and the latched publications, then announce
        readiness."""
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import MultiThreadedExecutor
        from std_msgs.msg import Bool

        from .action import THREADS as ACTION_THREADS
        from .action import SimulateStepsAction
        from .nodeservices import NodeServices, guard_node, sim_time_overrides
        from .publications import PublicationEndpoints
        from .qos import Qos
        from .receiver import Receiver
        from .sigros import SigRosEndpoints
        from .siminterfaces import SimInterfaces
        from .standard import StandardEndpoints

        self._sim = sim
        config = self.settings(sim)
        agents = sigros_agents(sim.world, config.sigros_agents)[0]
        node_name = self._node_name = self._args.node_name or self._node_name
        # the receiver thread wakes on a request and needs the GIL the simulation thread holds: hand it over
        # within 0.1 ms instead of Python's default 5 ms (restored in stop)
        self._switch = sys.getswitchinterval()
        sys.setswitchinterval(min(self._switch, SWITCH_INTERVAL))
        for name in ("sigcore.api", "sigcore.ros2"):
            logging.getLogger(name).addFilter(self._filter)
        self._context = Context()
        rclpy.init(context=self._context, args=self._args.rcl)  # remappings and log levels of --ros-args
        node = rclpy.create_node(node_name, context=self._context, parameter_overrides=sim_time_overrides())
        self._node = node
        qos = Qos(config.qos)
        receiver = Receiver(self._context)
        self._receiver = receiver
        # the node's own parameter and type description services, answered between steps like the others
        self.node_services = NodeServices(node, receiver, lambda: sim.stamp_ns())
        self.sigros = SigRosEndpoints(sim, node, receiver, qos, agents) if config.sigros else None
        with sim.events.owned_by(self):  # what they subscribe goes with the transport (stop)
            self.standard = StandardEndpoints(sim, node, receiver, qos, config) if config.standard else None
        self.interfaces = SimInterfaces(sim, node, receiver, config.sim_prefix, self._after_reset)
        # everything the core and the features declare (the agents' published topics, /tf_static, /map, ...)
        # the agents' published topics: those of the selected world agents, and of agents spawned later that the
        # selection's kinds and tags pick
        self._selection = config.sigros_agents
        self.publications = PublicationEndpoints(node, qos, agent_topics=self._selected if config.sigros else False,
                                                 before=self._clock_first)
        sim.publications.connect(self.publications)
        self._collect_endpoints()
        # the action server on its own node and executor (it needs rclpy's waitable machinery)
        self._action_node = rclpy.create_node(f"{node_name}_actions", context=self._context)
        guard_node(self._action_node)  # its parameter services run on the executor: never let them raise
        self.action = SimulateStepsAction(self._action_node, f"{config.sim_prefix}/simulate_steps",
                                          self.interfaces, self._submit)
        self._fixed = {f"{config.sim_prefix}/simulate_steps": "simulation_interfaces/action/SimulateSteps"}
        self.endpoints.update(self._fixed)
        self._executor = MultiThreadedExecutor(num_threads=ACTION_THREADS, context=self._context)
        self._executor.add_node(self._action_node)
        self._executor_thread = threading.Thread(target=self._spin_actions, name="sigcore-ros2-actions",
                                                 daemon=True)
        for topic in qos.unused():
            log.warning("qos override for '%s' names no topic of this world; topics: %s", topic,
                        ", ".join(sorted(t for t in self.endpoints if t.startswith("/"))))
        sim.events.subscribe("step", self._on_step, owner=self)
        sim.events.subscribe("entities", self._entities_changed, owner=self)
        sim.events.subscribe("world", self._world_changed, owner=self)
        receiver.start()
        self._executor_thread.start()
        if self.standard is not None:
            self.standard.publish_clock()
            self.standard.publish_state()
        self._ready = node.create_publisher(Bool, READY_TOPIC, qos.latched(READY_TOPIC))
        self._fixed[READY_TOPIC] = "std_msgs/msg/Bool"
        self.endpoints[READY_TOPIC] = "std_msgs/msg/Bool"
        self._announce(True)
        log.info("ROS 2 transport ready: %d endpoints", len(self.endpoints))

    def service(self, timeout: float) -> None:
        """Run the queued callbacks; while paused (``timeout`` > 0, no steps pending) wait for one first."""
        receiver = self._receiver
        if timeout > 0 and self._sim is not None and self._sim.control.pending_steps <= 0:
            standard = self.standard
            if standard is not None and standard.clock_behind:
                standard.publish_clock()  # paused: the last step's time at once (the wall-time limit may skip it)
            receiver.wait(timeout)
            now = time.monotonic()
            if standard is not None and now - self._idle_clock >= PAUSED_CLOCK_PERIOD:
                self._idle_clock = now  # paused: repeat the (unchanged) time for nodes that join late
                standard.publish_clock()
        if receiver.pending:
            receiver.drain()
        self._filter.summary(log)

    def stop(self) -> None:
        """Announce not-ready (and wait, briefly, until its subscribers have it), then answer what is still held, and
        close every endpoint: a client whose request fails because the run ended already knows that it ended."""
        if self._context is None:
            return
        try:
            if self._sim is not None:
                self._sim.events.detach(self)
                self._sim.publications.disconnect(self.publications)
            if not self.publications.flush(FLUSH_TIMEOUT):
                log.warning("some subscribers did not acknowledge the last messages within %g s", FLUSH_TIMEOUT)
            self._receiver.drain()
            if self.standard is not None and self.standard.clock_behind:
                self.standard.publish_clock()  # the final time
            self._announce(False)
            from rclpy.duration import Duration

            if not self._ready.wait_for_all_acked(Duration(nanoseconds=int(FLUSH_TIMEOUT * 1e9))):
                log.warning("some subscribers of %s did not acknowledge 'false' within %g s", READY_TOPIC,
                            FLUSH_TIMEOUT)
            self.interfaces.fail_waiters("the simulation stopped")
            if self.sigros is not None:
                self.sigros.refuse_held("the simulation stopped")
        finally:
            self.action.closing = True
            self._receiver.stop()
            self._executor.shutdown(timeout_sec=2.0)
            self._executor_thread.join(timeout=2.0)
            self._action_node.destroy_node()
            self._node.destroy_node()
            self._context.try_shutdown()
            self._context = None
            sys.setswitchinterval(self._switch)
            self._filter.summary(log, force=True)
            for name in ("sigcore.api", "sigcore.ros2"):
                logging.getLogger(name).removeFilter(self._filter)

    def _announce(self, ready: bool) -> None:
        """Publish readiness (latched), and hand it to the recorders (the publication contract's ``raw``)."""
        from rclpy.serialization import serialize_message
        from std_msgs.msg import Bool

        from .convert import offered

        data = serialize_message(Bool(data=ready))
        self._ready.publish(data)
        sim = self._sim
        if sim is not None and sim.publications.raw_wanted:
            sim.publications.raw(*offered(self._ready), sim.stamp_ns(), data)

    # ------------------------------------------------------------------ entities added and removed
    def _selected(self, agent: str) -> bool:
        """Whether ``agent`` gets its sig_ros endpoints (``sigros_agents``; asked for agents spawned later too).
        The agents' models are indexed by name once per world (spawning makes a new ``sim.world``), so asking
        for each of N agents costs O(N), not O(N^2)."""
        world = self._sim.world if self._sim is not None else None
        assert world is not None
        if self._index[0] is not world:
            self._index = (world, {a.name: a for a in world.agents})
        model = self._index[1].get(agent)
        return model is not None and selects_model(self._selection, model)

    def _entities_changed(self, change: EntityChange) -> None:
        """Entities were spawned or deleted (simulation thread): create the endpoints of the added agents and
        destroy those of the removed ones, as :meth:`start` does for the world's; their declared publications come
        and go through the core (:meth:`PublicationEndpoints.declare` and ``withdraw``)."""
        sim = self._sim
        assert sim is not None
        if change.removed:
            if self.sigros is not None:
                self.sigros.remove(change.removed, "the agent was deleted while the request was held")
            if self.standard is not None:
                self.standard.remove([name for name in change.removed if name in self.standard.owners])
        if change.added:
            if self.sigros is not None:
                self.sigros.add([name for name in change.added if name in sim.entities and self._selected(name)])
            if self.standard is not None:
                self.standard.add([name for name in change.added if sim.entities.get(name) is not None
                                   and sim.entities[name].kind == "robot"])
                self.standard.add_people([name for name in change.added if sim.entities.get(name) is not None
                                          and sim.entities[name].kind == "human"])
        elif self.standard is not None:
            self.standard.rebuild()
        self._collect_endpoints()
        if self.standard is not None:
            self.standard.publish_state()  # the new robots' joint states and TF at once

    def _world_changed(self, change: WorldChange) -> None:
        """A world is unloading (still complete) or was loaded (simulation thread). Unloading: pending step requests
        fail, every agent's sig_ros endpoints and every robot's topics go (held requests answered first). Loaded:
        the new world's agents get theirs, the state is STOPPED, /clock starts again at the new world's time 0 (its
        timestep may differ) and is published at once with the robots' state. The declared publications come and go
        through the core (``PublicationEndpoints.withdraw`` / ``declare``)."""
        sim = self._sim
        assert sim is not None
        if change.kind == "unloading":
            self.interfaces.fail_waiters(f"the world '{change.world.name}' was unloaded (load_world / unload_world)")
            if self.sigros is not None:
                self.sigros.remove(list(sim.entities), "the world was unloaded while the request was held")
            if self.standard is not None:
                self.standard.remove(list(self.standard.joints))
        else:
            self.interfaces.world_loaded()
            if self.sigros is not None:
                self.sigros.add([name for name in sim.entities if self._selected(name)])
            if self.standard is not None:
                self.standard.world_loaded()
                self.standard.publish_clock()
                self.standard.publish_state()
        self._collect_endpoints()

    def _collect_endpoints(self) -> None:
        """``self.endpoints``: every endpoint that exists now."""
        self.endpoints = {**(self.sigros.names if self.sigros else {}), **self.publications.names,
                          **(self.standard.topics if self.standard else {}), **self.interfaces.names,
                          **self._fixed}

    # ------------------------------------------------------------------ internals
    def _spin_actions(self) -> None:
        """Spin the action node until shutdown; an exception of one callback is logged (once per kind), never the
        end of the thread (rclpy's executor re-raises it from ``spin_once``)."""
        from rclpy.executors import ExternalShutdownException, ShutdownException

        executor, context = self._executor, self._context
        while context.ok() and not self.action.closing:
            try:
                executor.spin_once(timeout_sec=0.5)
            except (ExternalShutdownException, ShutdownException):
                break
            except Exception as e:  # e.g. an rclpy callback raising on a malformed request
                if not context.ok() or self.action.closing:
                    break
                kind = type(e).__name__
                log.error("a callback of node %s_actions raised %s: %s; still serving", self._node_name, kind,
                          clip(str(e), 200), extra=log_key(f"{self._node_name}_actions", kind))

    def _submit(self, job: Any) -> None:
        """Run ``job()`` on the simulation thread at the next service (from another thread)."""
        self._receiver.submit(job)

    def _on_step(self, sim: Simulation) -> None:
        if self.standard is not None:
            self.standard.on_step(sim)
        if self.interfaces.waiters:
            if self.standard is not None and self.standard.clock_behind:
                self.standard.publish_clock()  # a client stepping in lockstep sees the time of each step first
            self.interfaces.on_step(sim)
        if self.sigros is not None and self.sigros.held:
            self.sigros.poll_held()

    def _clock_first(self) -> None:
        """Put the current step's time on /clock before a declared publication goes out (the /clock policy: the
        core's and the features' stamped messages, e.g. SLAM's transforms, never run ahead of /clock)."""
        if self.standard is not None and self.standard.clock_behind:
            self.standard.publish_clock()

    def _after_reset(self) -> None:
        if self.standard is not None:
            self.standard.publish_state()
