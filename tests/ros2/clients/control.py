"""Pause, step, simulate_steps, reset, stop and play through simulation_interfaces, following /clock."""

from common import Client, emit
from rclpy.action import ActionClient
from rosgraph_msgs.msg import Clock
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import SimulationState
from simulation_interfaces.srv import (
    GetEntities,
    GetEntitiesStates,
    GetEntityState,
    GetSimulationState,
    GetSimulatorFeatures,
    ResetSimulation,
    SetEntityState,
    SetSimulationState,
    StepSimulation,
)

c = Client("control_probe")
c.wait_ready()
clocks = c.listen(Clock, "/clock")
c.wait_for(lambda: len(clocks) > 3, 10.0)
out = {}


def now():
    return clocks[-1].clock.sec + clocks[-1].clock.nanosec * 1e-9


def latest(seconds=0.3):
    c.spin(seconds)
    return now()


def state():
    return c.call(GetSimulationState, "/get_simulation_state").state.state


def set_state(s):
    return c.call(SetSimulationState, "/set_simulation_state", **{"state.state": s}).result.result


def pos(name):
    p = c.call(GetEntityState, "/get_entity_state", entity=name).state.pose.position
    return [p.x, p.y, p.z]


out["features"] = list(c.call(GetSimulatorFeatures, "/get_simulator_features").features.features)
out["initial_state"] = state()
out["pause"] = set_state(SimulationState.STATE_PAUSED)
out["paused_state"] = state()
out["pause_again"] = set_state(SimulationState.STATE_PAUSED)
c0 = latest(0.5)
out["clock_still"] = [c0, latest(0.5)]
out["step"] = c.call(StepSimulation, "/step_simulation", steps=100).result.result
out["after_step"] = latest()
action = ActionClient(c.node, SimulateSteps, "/simulate_steps")
action.wait_for_server(timeout_sec=10)
c.spin(1.0)  # let the feedback and status topics match too
feedback = []
goal_future = action.send_goal_async(SimulateSteps.Goal(steps=500),
                                     feedback_callback=lambda f: feedback.append(f.feedback.completed_steps))
c.executor.spin_until_future_complete(goal_future, timeout_sec=10)
result_future = goal_future.result().get_result_async()
c.executor.spin_until_future_complete(result_future, timeout_sec=30)
out["action"] = result_future.result().result.result.result
out["action_feedback"] = feedback
out["after_action"] = latest()
out["set_ball"] = c.call(SetEntityState, "/set_entity_state", entity="ball",
                         **{"state.pose.position.x": 0.5, "state.pose.position.y": -1.5,
                            "state.pose.position.z": 1.0, "state.pose.orientation.w": 1.0}).result.result
out["ball_set"] = pos("ball")
out["reset"] = c.call(ResetSimulation, "/reset_simulation").result.result
out["ball_reset"] = pos("ball")
out["after_reset"] = latest()
out["reset_time"] = c.call(ResetSimulation, "/reset_simulation", scope=ResetSimulation.Request.SCOPE_TIME).result.result
out["entities_b"] = list(c.call(GetEntities, "/get_entities", **{"filters.filter": "^b"}).entities)
out["entities_trash"] = list(c.call(GetEntities, "/get_entities", **{"filters.tags.tags": ["trash"]}).entities)
states = c.call(GetEntitiesStates, "/get_entities_states")
out["states"] = {n: [s.pose.position.x, s.pose.position.y] for n, s in zip(states.entities, states.states,
                                                                            strict=True)}
out["stop"] = set_state(SimulationState.STATE_STOPPED)
out["stopped_state"] = state()
out["play"] = set_state(SimulationState.STATE_PLAYING)
before_play = now()
out["after_play"] = [before_play, latest(0.5)]
out["quit"] = set_state(SimulationState.STATE_QUITTING)
emit(out)
