"""The ``simulate_steps`` action of simulation_interfaces: the steps of
:class:`~sigcore_ros2.siminterfaces.SimInterfaces`, with a cancel and one feedback per step."""

from __future__ import annotations

import logging
import threading
from typing import TYPE_CHECKING, Any

from simulation_interfaces.msg import Result, SimulationState

from sigcore.api.call import log_key
from sigcore.text import clip

from .exceptions import Refusal
from .siminterfaces import MAX_STEPS, SimInterfaces, StepWaiter

if TYPE_CHECKING:
    from rclpy.node import Node

log = logging.getLogger("sigcore.ros2")

FEEDBACK_DEPTH = 1000
"""History of the simulate_steps feedback publisher (reliable): a client that keeps up gets every step's feedback."""


def _result(code: int, message: str = "") -> Result:
    return Result(result=code, error_message=message)


class SimulateStepsAction:
    """The ``simulate_steps`` action on its own small node and executor thread.

    The execute callback hands the request to the simulation thread through ``submit`` and waits for it. The
    feedback is published on the simulation thread after each step of the goal, as the action definition says (one
    small message per step, only while a goal runs); the feedback publisher keeps :data:`FEEDBACK_DEPTH` messages.
    """

    def __init__(self, node: Node, name: str, interfaces: SimInterfaces, submit: Any) -> None:
        from rclpy.action import ActionServer, CancelResponse, GoalResponse
        from rclpy.callback_groups import ReentrantCallbackGroup
        from rclpy.qos import QoSProfile
        from simulation_interfaces.action import SimulateSteps

        self.interfaces = interfaces
        self.submit = submit
        self.closing = False
        self.SimulateSteps = SimulateSteps
        self.server = ActionServer(node, SimulateSteps, name, execute_callback=self._execute,
                                   goal_callback=lambda _g: GoalResponse.ACCEPT,
                                   cancel_callback=lambda _g: CancelResponse.ACCEPT,
                                   callback_group=ReentrantCallbackGroup(),
                                   feedback_pub_qos_profile=QoSProfile(depth=FEEDBACK_DEPTH))

    def _execute(self, goal: Any) -> Any:
        action = self.SimulateSteps
        steps = int(goal.request.steps)
        finished = threading.Event()
        outcome: dict[str, Any] = {}

        def start() -> None:
            i = self.interfaces
            try:
                i.require_world("simulate_steps")
            except Refusal as refusal:
                outcome["result"] = refusal.result()
                finished.set()
                return
            if i.state != SimulationState.STATE_PAUSED and not i.stopped:
                outcome["result"] = _result(Result.RESULT_OPERATION_FAILED,
                                            "simulate_steps needs the simulation paused")
                finished.set()
                return
            if steps > MAX_STEPS:
                outcome["result"] = _result(Result.RESULT_OPERATION_FAILED,
                                            f"{steps} steps is too many (max {MAX_STEPS})")
                finished.set()
                return
            if steps <= 0:
                outcome["result"] = _result(Result.RESULT_OK)
                finished.set()
                return

            def done(result: Result) -> None:
                outcome["result"] = result
                finished.set()

            def progress(completed: int) -> None:
                try:
                    goal.publish_feedback(action.Feedback(completed_steps=completed,
                                                          remaining_steps=steps - completed))
                except Exception as e:  # the goal handle went away (shutdown): never stop the simulation
                    log.warning("simulate_steps feedback failed: %s", clip(str(e), 200),
                                extra=log_key("simulate_steps", f"feedback {type(e).__name__}"))

            outcome["waiter"] = i.add_steps(steps, done, progress)

        self.submit(start)
        canceled = False
        while not finished.wait(0.02):
            if self.closing:
                outcome.setdefault("result", _result(Result.RESULT_OPERATION_FAILED, "the simulation stopped"))
                break
            if goal.is_cancel_requested and not canceled and "waiter" in outcome:
                canceled = True
                waiter = outcome["waiter"]

                def cancel(waiter: StepWaiter = waiter) -> None:
                    self.interfaces.cancel_steps(waiter)
                    outcome["result"] = _result(Result.RESULT_OPERATION_FAILED, "canceled")
                    finished.set()

                self.submit(cancel)
        result = outcome.get("result", _result(Result.RESULT_OPERATION_FAILED, "no result"))
        if canceled and result.error_message == "canceled":
            goal.canceled()
        elif result.result == Result.RESULT_OK:
            goal.succeed()
        else:
            goal.abort()
        return action.Result(result=result)
