"""Worlds at run time (the simulation runs worlds/cleanup.xml with --worlds tests/data/sim/world.xml): the world
features, get_available_worlds with filters and sources, get_current_world, load_world by path, by resource string
and by name, bad load requests, unload_world and the NO_WORLD state, then QUITTING.

Arguments: the absolute paths of worlds/cleanup.xml, worlds/arm6.xml and tests/data/sim/world.xml.
"""

import sys
from pathlib import Path

from common import Client, emit, todict
from rosgraph_msgs.msg import Clock
from sigcore_msgs import srv as sig
from simulation_interfaces.msg import EntityFilters, SimulationState, TagsFilter
from simulation_interfaces.srv import (
    GetAvailableWorlds,
    GetCurrentWorld,
    GetEntities,
    GetSimulationState,
    GetSimulatorFeatures,
    LoadWorld,
    SetSimulationState,
    SpawnEntity,
    StepSimulation,
    UnloadWorld,
)

CLEANUP, ARM6, DATA = (Path(p) for p in sys.argv[1:4])
TINY = ('<world name="tiny" timestep="0.005" tags="test" description="a box on the floor">\n'
        '  <object name="crate" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1 0 0 0"/>\n</world>\n')
BAD = {
    "empty": {},
    "sdf": {"resource_string": "<sdf version='1.9'><world name='w'/></sdf>"},
    "malformed": {"resource_string": "<world name='x'><object"},
    "urdf": {"resource_string": "<world name='x'><robot name='r' urdf='/nonexistent/r.urdf'/></world>"},
    "element": {"resource_string": "<world name='x'><spaceship/></world>"},
    "name": {"uri": "no_such_world"},
}
ROBOT_000 = {"/robot_000_get_obj_position", "/robot_000/cmd_vel", "/robot_000/joint_states"}
ARM_0 = {"/arm_0_get_obj_position", "/arm_0/joint_states"}
GRAPH_WAIT = 30.0
"""Longest wait for the graph or /clock to show a change [s of wall time]: a wide margin for a loaded machine (a
change normally shows within a second); only a failure waits that long."""

c = Client("worlds_probe")
c.wait_ready()
clocks = c.listen(Clock, "/clock")
out: dict = {}


def result(response) -> dict:
    if response is None:
        return {"result": None, "message": "no answer"}
    return {"result": response.result.result, "message": response.result.error_message}


def state() -> int:
    return c.call(GetSimulationState, "/get_simulation_state").state.state


def set_state(s: int) -> dict:
    return result(c.call(SetSimulationState, "/set_simulation_state", state=SimulationState(state=s)))


def entities() -> list:
    got = c.call(GetEntities, "/get_entities", filters=EntityFilters())
    return list(got.entities) if got is not None else None


def current() -> dict:
    got = c.call(GetCurrentWorld, "/get_current_world")
    return {**result(got), "name": got.world.name, "uri": got.world.world_resource.uri,
            "text": got.world.world_resource.resource_string, "tags": list(got.world.tags),
            "description": got.world.description}


def available(**fields) -> dict:
    got = c.call(GetAvailableWorlds, "/get_available_worlds", **fields)
    return {**result(got), "worlds": [{"name": w.name, "uri": w.world_resource.uri, "tags": list(w.tags),
                                       "description": w.description} for w in got.worlds]}


def load(**fields) -> dict:
    got = c.call(LoadWorld, "/load_world", timeout=60.0, **fields)
    return {**result(got), "name": got.world.name if got is not None else None}


def graph() -> set[str]:
    """The simulation node's topics and services."""
    return c.graph()


def clock() -> float:
    """The latest /clock after 0.3 s of spinning [s]."""
    c.spin(0.3)
    return clocks[-1].clock.sec + clocks[-1].clock.nanosec * 1e-9 if clocks else -1.0


def position(service: str) -> dict | None:
    got = c.call(sig.GetObjPosition, service, name="")
    return todict(got) if got is not None else None


# what is announced and listed
out["features"] = sorted(c.call(GetSimulatorFeatures, "/get_simulator_features").features.features)
out["all"] = available()
out["filtered"] = available(filter=TagsFilter(tags=["indoor", "home"], filter_mode=TagsFilter.FILTER_MODE_ALL))
out["any"] = available(filter=TagsFilter(tags=["arm", "nothing"], filter_mode=TagsFilter.FILTER_MODE_ANY))
out["bad_mode"] = available(filter=TagsFilter(tags=["arm"], filter_mode=7))
out["missing_source"] = available(additional_sources=["/no/such/worlds"])
out["missing_continue"] = available(additional_sources=["/no/such/worlds"], continue_on_error=True)
out["remote_source"] = available(additional_sources=["https://example.com/worlds"])
out["file_uri_source"] = available(additional_sources=[DATA.parent.as_uri()])
out["current"] = current()
c.wait_for(lambda: ROBOT_000 <= graph(), GRAPH_WAIT)
out["robot_000_before"] = sorted(ROBOT_000 & graph())

# load arm6 by path: STOPPED at time 0, arm_0's endpoints replace robot_000's; PLAYING advances /clock again
out["clock_before"] = clock()
out["load_arm6"] = load(uri=str(ARM6))
out["state_after_load"] = state()
out["entities_arm6"] = entities()
out["clock_after_load"] = clock()
c.wait_for(lambda: ARM_0 <= graph() and not (ROBOT_000 & graph()), GRAPH_WAIT)
out["arm_0"] = sorted(ARM_0 & graph())
out["robot_000_after"] = sorted(ROBOT_000 & graph())
out["arm_position"] = position("/arm_0_get_obj_position")
out["current_arm6"] = current()
out["play"] = set_state(SimulationState.STATE_PLAYING)
c.wait_for(lambda: bool(clocks) and clocks[-1].clock.sec + clocks[-1].clock.nanosec * 1e-9 > 0.2, GRAPH_WAIT)
out["clock_playing"] = clock()

# load a world given as text (timestep 0.005) while a long step request is pending: the request fails naming the
# world; stepping 100 times from STOPPED puts /clock at 0.5 s
out["pause"] = set_state(SimulationState.STATE_PAUSED)
stepper = c.node.create_client(StepSimulation, "/step_simulation")
stepper.wait_for_service(timeout_sec=GRAPH_WAIT)
pending = stepper.call_async(StepSimulation.Request(steps=1_000_000))  # 2000 s at real time: still pending
c.spin(0.3)
out["load_text"] = load(resource_string=TINY)
c.executor.spin_until_future_complete(pending, timeout_sec=GRAPH_WAIT)
out["pending_step"] = result(pending.result() if pending.done() else None)
out["state_text"] = state()
out["current_text"] = current()
c.wait_for(lambda: "/crate_get_obj_position" in graph(), GRAPH_WAIT)
out["crate_endpoint"] = "/crate_get_obj_position" in graph()
out["entities_text"] = entities()
out["step_text"] = result(c.call(StepSimulation, "/step_simulation", timeout=30.0, steps=100))
out["clock_text"] = clock()

# bad requests: each with its code, the running world unchanged
out["bad"] = {case: load(**fields) for case, fields in BAD.items()}
out["bad"]["element_strict"] = load(fail_on_unsupported_element=True, **BAD["element"])
out["bad"]["urdf_ignore"] = load(ignore_missing_or_unsupported_assets=True, **BAD["urdf"])
out["current_after_bad"] = current()
out["entities_after_bad"] = entities()

# unload: NO_WORLD, nothing steps or spawns; load the clean-up world again by name
out["unload"] = result(c.call(UnloadWorld, "/unload_world"))
out["state_unloaded"] = state()
out["current_unloaded"] = current()
out["entities_unloaded"] = entities()
out["clock_unloaded"] = clock()
c.wait_for(lambda: not (ARM_0 | {"/crate_get_obj_position"}) & graph(), GRAPH_WAIT)
out["graph_unloaded"] = sorted(t for t in graph() if t in ("/tf_static", "/sigcore/scene", "/crate_get_obj_position"))
out["play_unloaded"] = set_state(SimulationState.STATE_PLAYING)
out["step_unloaded"] = result(c.call(StepSimulation, "/step_simulation", steps=1))
out["spawn_unloaded"] = result(c.call(SpawnEntity, "/spawn_entity", name="b",
                                      resource_string='<object shape="box" size="0.1 0.1 0.1"/>'))
out["unload_again"] = result(c.call(UnloadWorld, "/unload_world"))
out["load_cleanup"] = load(uri="cleanup")
out["state_cleanup"] = state()
c.wait_for(lambda: ROBOT_000 <= graph(), GRAPH_WAIT)
out["robot_000_back"] = sorted(ROBOT_000 & graph())
out["robot_position"] = position("/robot_000_get_obj_position")
out["current_cleanup"] = current()

# still serving at the end; QUITTING ends the run
out["state_end"] = state()
out["quit"] = set_state(SimulationState.STATE_QUITTING)
emit(out)
