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
MAX_RUNNING = 8
"""Most simulate_steps goals running at once [goals]; a goal beyond them is rejected. Each running goal holds one
executor thread while it waits for its steps; the executor has :data:`FREE_THREADS` more, so the action's own
services (get_result, cancel_goal, send_goal) and the node's parameter services always have a thread to answer on."""
FREE_THREADS = 4
"""Executor threads never held by a running goal [threads]."""
THREADS = MAX_RUNNING + FREE_THREADS
"""Threads of the action node's executor [threads]."""


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
        self._running = 0
        self._lock = threading.Lock()
        self._accept, self._reject = GoalResponse.ACCEPT, GoalResponse.REJECT
        self.server = ActionServer(node, SimulateSteps, name, execute_callback=self._execute,
                                   goal_callback=self._goal,
                                   cancel_callback=lambda _g: CancelResponse.ACCEPT,
                                   callback_group=ReentrantCallbackGroup(),
                                   feedback_pub_qos_profile=QoSProfile(depth=FEEDBACK_DEPTH))

    def _goal(self, _request: Any) -> Any:
        """Accept a goal while fewer than :data:`MAX_RUNNING` run (it counts as running from here on)."""
        with self._lock:
            if self._running >= MAX_RUNNING:
                log.warning("simulate_steps: a goal was rejected: %d goals are running (at most %d at once)",
                            self._running, MAX_RUNNING, extra=log_key("simulate_steps", "too many goals"))
                return self._reject
            self._running += 1
            return self._accept

    def _execute(self, goal: Any) -> Any:
        try:
            return self._run(goal)
        finally:
            with self._lock:
                self._running -= 1

    def _run(self, goal: Any) -> Any:
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

        def guarded_start() -> None:
            try:
                start()
            except Exception as e:  # the goal ends (its thread is freed); the receiver logs the error
                outcome.setdefault("result", _result(Result.RESULT_OPERATION_FAILED,
                                                     f"simulate_steps failed: {type(e).__name__}: {clip(str(e), 200)}"))
                finished.set()
                raise

        self.submit(guarded_start)
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
