"""The standard ``simulation_interfaces`` (Jazzy 1.5) services and the ``simulate_steps`` action.

Supported (and listed by get_simulator_features): spawning (one entity or several in one call, from a URI or a
resource string: URDF, a world-format element, OBJ and STL meshes, ``model://`` spawnables, with a namespace) and
deleting while running, spawnables, entity filters by name, category, tags and bounds (box and sphere), entity
information getting and setting (category, description, tags), entity bounds (an axis-aligned box in ``world``),
named poses and their bounds, entity state getting and setting, reset (state scope, and the spawned scope that
deletes what was spawned; time never goes back), simulation state getting and setting (stopped, playing, paused,
quitting), single and multiple steps, the SimulateSteps action with one feedback per step, worlds (the available
ones, filtered by tags; the current one; loading by URI, name or resource string; unloading: state NO_WORLD until a
world is loaded). Not supported: convex-hull bounds filters (FEATURE_UNSUPPORTED). The core spawns, deletes, loads
and unloads (``sigcore.sim.spawn``, ``sigcore.world.catalogue``); this module maps requests and refusal codes. The
read side (filters, information, bounds, named poses) is in ``siminfo.py``, the world services in ``worlds.py``,
the ``simulate_steps`` action (on the steps of :class:`SimInterfaces`) in ``action.py``.
"""

from __future__ import annotations

import logging
import math
from typing import TYPE_CHECKING, Any

from simulation_interfaces.msg import (
    Bounds,
    EntityState,
    Result,
    SimulationState,
    SimulatorFeatures,
    Spawnable,
    SpawnResult,
)
from simulation_interfaces.srv import (
    DeleteEntity,
    GetEntities,
    GetEntitiesStates,
    GetEntityBounds,
    GetEntityInfo,
    GetEntityState,
    GetNamedPoseBounds,
    GetNamedPoses,
    GetSimulationState,
    GetSimulatorFeatures,
    GetSpawnables,
    ResetSimulation,
    SetEntityInfo,
    SetEntityState,
    SetSimulationState,
    SpawnEntities,
    SpawnEntity,
    StepSimulation,
)

from sigcore.agent.exceptions import ApiError
from sigcore.api.call import log_key
from sigcore.text import clip, quote
from sigcore.world.exceptions import SpawnRefusal
from sigcore.world.resources import RefusalCode, SpawnRequest

from .convert import finite, stamp
from .exceptions import Refusal
from .siminfo import EntityQueries, bounds_box
from .worlds import SERVICES as WORLD_SERVICES
from .worlds import WorldServices

if TYPE_CHECKING:
    from rclpy.node import Node

    from sigcore.sim.simulation import Simulation

    from .receiver import Receiver

log = logging.getLogger("sigcore.ros2")

F = SimulatorFeatures
SUPPORTED = [F.NAMED_POSES, F.POSE_BOUNDS, F.ENTITY_TAGS, F.ENTITY_BOUNDS, F.ENTITY_BOUNDS_BOX,
             F.ENTITY_CATEGORIES, F.ENTITY_STATE_GETTING, F.ENTITY_STATE_SETTING, F.ENTITY_INFO_GETTING,
             F.ENTITY_INFO_SETTING, F.SIMULATION_RESET, F.SIMULATION_RESET_STATE, F.SIMULATION_STATE_GETTING,
             F.SIMULATION_STATE_SETTING, F.SIMULATION_STATE_PAUSE, F.STEP_SIMULATION_SINGLE,
             F.STEP_SIMULATION_MULTIPLE, F.STEP_SIMULATION_ACTION, F.SPAWNING, F.DELETING, F.SPAWNING_ENTITIES,
             F.SPAWNING_RESOURCE_STRING, F.SPAWNABLES, F.SIMULATION_RESET_SPAWNED, F.WORLD_LOADING,
             F.WORLD_RESOURCE_STRING, F.WORLD_TAGS, F.WORLD_UNLOADING, F.WORLD_INFO_GETTING, F.AVAILABLE_WORLDS]
"""What get_simulator_features announces: only what is really implemented."""

SPAWN_FORMATS = ["urdf", "sigcore", "obj", "stl"]
"""What spawn_entity's ``uri`` and ``resource_string`` may hold: URDF, a world-format element (``sigcore``), meshes."""

SPAWN_CODES: dict[RefusalCode, int] = {
    "NAME_NOT_UNIQUE": SpawnResult.NAME_NOT_UNIQUE, "NAME_INVALID": SpawnResult.NAME_INVALID,
    "UNSUPPORTED_FORMAT": SpawnResult.UNSUPPORTED_FORMAT, "NO_RESOURCE": SpawnResult.NO_RESOURCE,
    "NAMESPACE_INVALID": SpawnResult.NAMESPACE_INVALID, "RESOURCE_PARSE_ERROR": SpawnResult.RESOURCE_PARSE_ERROR,
    "MISSING_ASSETS": SpawnResult.MISSING_ASSETS, "UNSUPPORTED_ASSETS": SpawnResult.UNSUPPORTED_ASSETS,
    "INVALID_POSE": SpawnResult.INVALID_POSE, "NOT_FOUND": Result.RESULT_NOT_FOUND,
    "OPERATION_FAILED": Result.RESULT_OPERATION_FAILED,
}
"""The core's refusal codes (:data:`sigcore.world.exceptions.RefusalCode`) as simulation_interfaces result codes (the
SpawnEntity and SpawnResult constants are the same numbers)."""

SERVICES = {
    "get_simulator_features": GetSimulatorFeatures, "get_entities": GetEntities,
    "get_entity_state": GetEntityState, "set_entity_state": SetEntityState,
    "get_entities_states": GetEntitiesStates, "get_entity_info": GetEntityInfo, "set_entity_info": SetEntityInfo,
    "get_entity_bounds": GetEntityBounds, "get_named_poses": GetNamedPoses,
    "get_named_pose_bounds": GetNamedPoseBounds, "spawn_entity": SpawnEntity, "spawn_entities": SpawnEntities,
    "delete_entity": DeleteEntity, "get_spawnables": GetSpawnables,
    "get_simulation_state": GetSimulationState, "set_simulation_state": SetSimulationState,
    "reset_simulation": ResetSimulation, "step_simulation": StepSimulation, **WORLD_SERVICES,
}


MAX_STEPS = 10_000_000
"""Most steps one step_simulation request or simulate_steps goal may ask for [steps]."""


def _result(code: int, message: str = "") -> Result:
    return Result(result=code, error_message=message)


class StepWaiter:
    """Steps requested through step_simulation or simulate_steps, answered when reached.

    Args:
        target: The step count at which the request is done.
        steps: How many steps it asked for (they are the last ``steps`` before ``target``).
        done: Called with the Result when the target step is reached or the request fails.
        progress: Called with the number of its steps completed after each of them (simulate_steps' feedback).
    """

    def __init__(self, target: int, steps: int, done: Any, progress: Any = None) -> None:
        self.target = target
        self.steps = steps
        self.done = done
        self.progress = progress


class SimInterfaces:
    """The simulation_interfaces services (run on the simulation thread through the receiver).

    Args:
        sim: The simulation.
        node: The node that owns the services.
        receiver: Where the services are registered.
        prefix: Namespace of the services (``""`` for the root).
        on_reset: Called after a reset (to republish state).
    """

    def __init__(self, sim: Simulation, node: Node, receiver: Receiver, prefix: str, on_reset: Any) -> None:
        self.sim = sim
        self.stopped = False
        self.waiters: list[StepWaiter] = []
        self.on_reset = on_reset
        self.names: dict[str, str] = {}
        self.queries = EntityQueries(sim)
        self.worlds = WorldServices(sim)
        for name, srv_type in SERVICES.items():
            full = f"{prefix}/{name}"
            srv = node.create_service(srv_type, full, lambda *_: None)
            method = (getattr(self, f"_{name}", None) or getattr(self.queries, name, None)
                      or getattr(self.worlds, name))
            receiver.add_service(srv, self._bind(srv, method))
            self.names[full] = f"simulation_interfaces/srv/{srv_type.__name__}"

    def _bind(self, srv: Any, method: Any) -> Any:
        def handle(request: Any, header: Any) -> None:
            response = srv.srv_type.Response()
            try:
                answered = method(request, response, lambda r: srv.send_response(r, header))
            except Refusal as refusal:
                response = srv.srv_type.Response()
                response.result = refusal.result()
                answered = False
            except Exception as e:  # a bug must not stop the simulation
                kind = f"internal error {type(e).__name__}"
                log.exception("%s failed", srv.srv_name, extra=log_key(srv.srv_name, kind))
                response = srv.srv_type.Response()
                response.result = _result(Result.RESULT_OPERATION_FAILED,
                                          f"internal error: {type(e).__name__}: {clip(str(e), 200)}")
                answered = False
            if answered is False:
                result = getattr(response, "result", None)
                if result is not None and result.result not in (Result.RESULT_OK,):
                    log.warning("%s refused (logged once per kind): %s", srv.srv_name, clip(result.error_message),
                                extra=log_key(srv.srv_name, f"result {result.result}"))
                srv.send_response(response, header)

        return handle

    # ------------------------------------------------------------------ state
    @property
    def state(self) -> int:
        """The SimulationState constant of the simulation now."""
        c = self.sim.control
        if not self.sim.worlds.loaded:
            return SimulationState.STATE_QUITTING if c.stopping else SimulationState.STATE_NO_WORLD
        if self.stopped:
            return SimulationState.STATE_STOPPED
        if c.stopping:
            return SimulationState.STATE_QUITTING
        return SimulationState.STATE_PAUSED if c.paused else SimulationState.STATE_PLAYING

    def on_step(self, sim: Simulation) -> None:
        """Answer step requests whose target step was reached."""
        if self.waiters:
            for w in self.waiters:
                if w.progress is not None:
                    completed = sim.step_count - (w.target - w.steps)
                    if 0 < completed <= w.steps:
                        w.progress(completed)
            done = [w for w in self.waiters if sim.step_count >= w.target]
            if done:
                self.waiters = [w for w in self.waiters if sim.step_count < w.target]
                for w in done:
                    w.done(_result(Result.RESULT_OK))

    def world_loaded(self) -> None:
        """A world was loaded (the ``world`` event): STOPPED (the core leaves it paused at its time 0)."""
        self.stopped = True

    def require_world(self, what: str) -> None:
        """Refuse ``what`` when no world is loaded.

        Raises:
            Refusal: INCORRECT_STATE saying ``what`` needs a world (answered by the service wrapper).
        """
        if not self.sim.worlds.loaded:
            raise Refusal(Result.RESULT_INCORRECT_STATE, f"{what} refused: no world is loaded; load one first "
                                                         "(load_world)")

    def fail_waiters(self, why: str) -> None:
        """Answer every pending step request with a failure."""
        waiters, self.waiters = self.waiters, []
        for w in waiters:
            w.done(_result(Result.RESULT_OPERATION_FAILED, why))

    # ------------------------------------------------------------------ services: (request, response, reply)
    # Each returns False to have ``response`` sent now, or True if it answers later through ``reply``.
    def _get_simulator_features(self, req: Any, res: Any, reply: Any) -> bool:
        res.features.features = list(SUPPORTED)
        res.features.spawn_formats = list(SPAWN_FORMATS)
        res.features.custom_info = ("sigcore: time never goes back on reset (SCOPE_TIME unsupported); "
                                    "spawn_formats: urdf (file, package:// or text), sigcore (one <robot>, <object> "
                                    "or <human> element of the world format), obj and stl meshes, model://NAME "
                                    "spawnables; worlds: the sigcore world format only (load_world uri: a path, "
                                    "file:// or package:// URI or an available world's name; elements and assets "
                                    "are never ignored), local sources only; sig_ros API as <agent>_<suffix>")
        return False

    def _get_entities(self, req: Any, res: Any, reply: Any) -> bool:
        res.entities = self.queries.select(req.filters)
        res.result = _result(Result.RESULT_OK)
        return False

    def _entity_state(self, name: str) -> EntityState:
        backend = self.sim.backend
        pos, quat = backend.get_pose(name)
        lin, ang = backend.get_velocity(name)
        st = EntityState()
        st.header.stamp, st.header.frame_id = stamp(self.sim.step_count, round(self.sim.dt * 1e9)), "world"
        p = st.pose
        p.position.x, p.position.y, p.position.z = (float(v) for v in pos)
        p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z = (float(v) for v in quat)
        st.twist.linear.x, st.twist.linear.y, st.twist.linear.z = (float(v) for v in lin)
        st.twist.angular.x, st.twist.angular.y, st.twist.angular.z = (float(v) for v in ang)
        return st

    def _unknown(self, name: str, res: Any) -> bool:
        if name in self.sim.entities.names:
            return False
        res.result = _result(Result.RESULT_NOT_FOUND,
                             f"no entity {quote(name)}; entities: {', '.join(self.sim.entities.names)}")
        return True

    def _get_entity_state(self, req: Any, res: Any, reply: Any) -> bool:
        if not self._unknown(req.entity, res):
            res.state = self._entity_state(req.entity)
            res.result = _result(Result.RESULT_OK)
        return False

    def _get_entities_states(self, req: Any, res: Any, reply: Any) -> bool:
        names = self.queries.select(req.filters)
        res.entities = names
        res.states = [self._entity_state(n) for n in names]
        res.result = _result(Result.RESULT_OK)
        return False

    def _set_entity_state(self, req: Any, res: Any, reply: Any) -> bool:
        self.require_world("set_entity_state")
        if self._unknown(req.entity, res):
            return False
        st = req.state
        if st.header.frame_id not in ("", "world"):
            res.result = _result(Result.RESULT_OPERATION_FAILED,
                                 f"frame {quote(st.header.frame_id)} is not supported; use '' or 'world'")
            return False
        p, o = st.pose.position, st.pose.orientation
        q = (o.w, o.x, o.y, o.z)
        norm = math.sqrt(sum(v * v for v in q)) if finite(*q) else 0.0
        if not finite(p.x, p.y, p.z) or norm < 1e-9:
            res.result = _result(SetEntityState.Response.INVALID_POSE,
                                 "pose must be finite with a non-zero quaternion (w=1 for no rotation)")
            return False
        lin, ang = st.twist.linear, st.twist.angular
        twist = (lin.x, lin.y, lin.z, ang.x, ang.y, ang.z)
        if not finite(*twist):
            res.result = _result(Result.RESULT_OPERATION_FAILED, "twist must be finite")
            return False
        moving = any(v != 0.0 for v in twist)
        if moving and not self.sim.entities.mode(req.entity, "dynamics"):
            res.result = _result(Result.RESULT_OPERATION_FAILED,
                                 f"'{req.entity}' is static (dynamics off): it cannot be given a velocity")
            return False
        dynamic = self.sim.entities.mode(req.entity, "dynamics")
        try:
            self.sim.inputs.entity_state(req.entity, (p.x, p.y, p.z), q, (lin.x, lin.y, lin.z) if dynamic else None,
                                         (ang.x, ang.y, ang.z) if dynamic else None)
        except ApiError as e:
            res.result = _result(Result.RESULT_OPERATION_FAILED, str(e))
            return False
        res.result = _result(Result.RESULT_OK)
        return False

    def _require_changeable(self, what: str) -> None:
        """Refuse ``what`` (spawning, deleting) when the simulation is quitting, has no world or is stopped.

        Raises:
            Refusal: OPERATION_FAILED (quitting, stopped) or INCORRECT_STATE (no world), saying why.
        """
        if self.sim.control.stopping:
            raise Refusal(Result.RESULT_OPERATION_FAILED, f"{what} refused: the simulation is quitting")
        self.require_world(what)
        if self.stopped:
            raise Refusal(Result.RESULT_OPERATION_FAILED, f"{what} refused: the simulation is stopped; set it "
                                                          "PLAYING or PAUSED first (set_simulation_state)")

    def _spawn_entity(self, req: Any, res: Any, reply: Any) -> bool:
        self._require_changeable("spawning")
        request = _spawn_request(req, req.uri, req.resource_string)
        outcome = self.sim.inputs.spawn([request], what=f"spawn_entity {req.name or req.uri}")[0]
        res.result, res.entity_name = _spawned(outcome)
        return False

    def _spawn_entities(self, req: Any, res: Any, reply: Any) -> bool:
        self._require_changeable("spawning")
        requests = [_spawn_request(r, r.entity_resource.uri, r.entity_resource.resource_string)
                    for r in req.spawn_requests]
        outcomes = self.sim.inputs.spawn(requests, what=f"spawn_entities ({len(requests)})") if requests else []
        res.results = []
        for outcome in outcomes:
            result, name = _spawned(outcome)
            res.results.append(SpawnResult(result=result, entity_name=name))
        failed = [i for i, o in enumerate(outcomes) if isinstance(o, SpawnRefusal)]
        if failed:
            added = len(outcomes) - len(failed)
            first = outcomes[failed[0]]
            res.result = _result(SpawnEntities.Response.ENTITIES_SPAWN_FAILED,
                                 f"{len(failed)} of {len(outcomes)} spawn requests failed (indices "
                                 f"{', '.join(map(str, failed))}; {added} spawned); the first: {first}; see results")
        else:
            res.result = _result(Result.RESULT_OK)
        return False

    def _delete_entity(self, req: Any, res: Any, reply: Any) -> bool:
        self._require_changeable("deleting")
        try:
            self.sim.inputs.delete([req.entity], what=f"delete_entity {req.entity}")
        except SpawnRefusal as refusal:
            res.result = _result(SPAWN_CODES[refusal.code], str(refusal))
            return False
        res.result = _result(Result.RESULT_OK)
        return False

    def _get_spawnables(self, req: Any, res: Any, reply: Any) -> bool:
        res.spawnables = [Spawnable(uri=s.uri, description=s.description,
                                    spawn_bounds=bounds_box(*s.bounds) if s.bounds is not None
                                    else Bounds(type=Bounds.TYPE_EMPTY))
                          for s in self.sim.entities.spawnables()]
        unknown = [str(source) for source in req.sources]
        res.result = _result(Result.RESULT_OK, f"sources not searched (sigcore lists worlds/models and its plugins' "
                                               f"spawnables only): {', '.join(map(quote, unknown))}" if unknown
                             else "")
        return False

    def _get_simulation_state(self, req: Any, res: Any, reply: Any) -> bool:
        res.state.state = self.state
        res.result = _result(Result.RESULT_OK)
        return False

    def _set_simulation_state(self, req: Any, res: Any, reply: Any) -> bool:
        target, now, c = req.state.state, self.state, self.sim.control
        s = SimulationState
        if now == s.STATE_NO_WORLD and target != s.STATE_QUITTING:
            res.result = _result(Result.RESULT_INCORRECT_STATE,
                                 f"state {target} cannot be set: no world is loaded (state 4 NO_WORLD); load one "
                                 "first (load_world), or set 3 quitting")
            return False
        if target == now:
            res.result = _result(SetSimulationState.Response.ALREADY_IN_TARGET_STATE, "already in that state")
            return False
        if target == s.STATE_PLAYING:  # the run control's verbs: the same semantics as the viewer's buttons
            self.stopped = False
            c.play()  # steps still requested are taken by playing: their requests are answered as they pass
        elif target == s.STATE_PAUSED:
            self.stopped = False
            c.pause()
            self.fail_waiters("the simulation was paused before the requested steps were taken")
        elif target == s.STATE_STOPPED:
            c.pause()
            self.fail_waiters("the simulation was stopped")
            c.request_reset()
            self.stopped = True
            self.on_reset()
        elif target == s.STATE_QUITTING:
            self.fail_waiters("the simulation is quitting")
            c.stop("request")
        else:
            res.result = _result(Result.RESULT_FEATURE_UNSUPPORTED,
                                 f"state {target} cannot be set; valid: 0 stopped, 1 playing, 2 paused, 3 quitting "
                                 "(no world: unload_world; loading: load_world)")
            return False
        res.result = _result(Result.RESULT_OK)
        return False

    def _reset_simulation(self, req: Any, res: Any, reply: Any) -> bool:
        scope = req.scope
        r = ResetSimulation.Request
        self.require_world("reset_simulation")
        if scope == r.SCOPE_TIME:
            res.result = _result(Result.RESULT_FEATURE_UNSUPPORTED,
                                 "sigcore's time never goes back: reset the state (SCOPE_STATE, SCOPE_SPAWNED or "
                                 "SCOPE_ALL)")
            return False
        # SCOPE_STATE alone keeps the spawned entities (back to their state as spawned); DEFAULT, ALL and any scope
        # with SCOPE_SPAWNED also delete them and bring back deleted world-file entities (time never goes back)
        self.sim.control.request_reset(despawn=scope in (r.SCOPE_DEFAULT, r.SCOPE_ALL) or bool(scope & r.SCOPE_SPAWNED))
        self.on_reset()
        res.result = _result(Result.RESULT_OK)
        return False

    def _step_simulation(self, req: Any, res: Any, reply: Any) -> bool:
        steps = int(req.steps)
        self.require_world("step_simulation")
        if self.state != SimulationState.STATE_PAUSED and not self.stopped:
            res.result = _result(Result.RESULT_OPERATION_FAILED,
                                 "step_simulation needs the simulation paused (set_simulation_state PAUSED)")
            return False
        if steps <= 0:
            res.result = _result(Result.RESULT_OK)
            return False
        if steps > MAX_STEPS:
            res.result = _result(Result.RESULT_OPERATION_FAILED, f"{steps} steps is too many (max {MAX_STEPS})")
            return False
        self.add_steps(steps, lambda result: reply(StepSimulation.Response(result=result)))
        return True

    def add_steps(self, steps: int, done: Any, progress: Any = None) -> StepWaiter:
        """Queue ``steps`` steps (simulation paused); ``done(Result)`` is called when they are taken, and
        ``progress(completed)`` after each of them."""
        c = self.sim.control
        self.stopped = False
        c.step(steps)  # pauses (from STOPPED: PAUSED)
        waiter = StepWaiter(self.sim.step_count + c.pending_steps, steps, done, progress)
        self.waiters.append(waiter)
        return waiter

    def cancel_steps(self, waiter: StepWaiter) -> None:
        """Drop the steps of ``waiter`` that were not taken yet."""
        if waiter in self.waiters:
            self.waiters.remove(waiter)
            remaining = max(0, waiter.target - self.sim.step_count)
            self.sim.control.drop_steps(remaining)


def _spawn_request(req: Any, uri: str, resource: str) -> SpawnRequest:
    """The core's request for a SpawnEntity service request or message (``uri``, ``resource``: where each keeps
    them)."""
    p, o = req.initial_pose.pose.position, req.initial_pose.pose.orientation
    return SpawnRequest(name=req.name, uri=uri, resource=resource if not uri else "",
                        xyz=(float(p.x), float(p.y), float(p.z)),
                        wxyz=(float(o.w), float(o.x), float(o.y), float(o.z)),
                        frame=req.initial_pose.header.frame_id, namespace=req.entity_namespace,
                        allow_renaming=bool(req.allow_renaming))


def _spawned(outcome: str | SpawnRefusal) -> tuple[Result, str]:
    """The Result and entity name of one spawn's outcome (a name, or the core's refusal)."""
    if isinstance(outcome, SpawnRefusal):
        return _result(SPAWN_CODES[outcome.code], str(outcome)), ""
    return _result(Result.RESULT_OK), outcome
