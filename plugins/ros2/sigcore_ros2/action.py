"""The ``simulate_steps`` action of simulation_interfaces: the steps of
:class:`~sigcore_ros2.siminterfaces.SimInterfaces`, with a cancel and one feedback per step."""

from __future__ import annotations

import functools
import logging
import threading
import time
from typing import TYPE_CHECKING, Any

from simulation_interfaces.msg import Result, SimulationState

from sigcore.api.call import log_key
from sigcore.text import clip

from . import responses
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
        self.server = _patient(ActionServer)(node, SimulateSteps, name, execute_callback=self._execute,
                                             goal_callback=self._goal,
                                             cancel_callback=lambda _g: CancelResponse.ACCEPT,
                                             callback_group=ReentrantCallbackGroup(),
                                             feedback_pub_qos_profile=QoSProfile(depth=FEEDBACK_DEPTH))
        self.server.sigcore_name = name

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


@functools.cache
def _patient(base: type) -> type:
    """``rclpy.action.ActionServer`` whose result responses wait for their client, as :mod:`.responses` does for
    services: rclpy sends a ``get_result`` response once, and rmw drops it when the client's response reader is not
    discovered yet (on a loaded machine a client calls ``get_result`` right after its goal was accepted, or before any
    goal, seconds before that); the client then waits for its result forever. Here a send that fails is tried again
    every :data:`~.responses.RETRY_PERIOD` until :data:`~.responses.GIVE_UP` (then a warning names the action). The
    tries block one of the action node's executor threads (:data:`FREE_THREADS` are never held by goals)."""

    class PatientActionServer(base):  # type: ignore[valid-type,misc]
        async def _execute_get_result_request(self, request_header_and_message: Any) -> None:
            header, request = request_header_and_message
            future = self._result_futures.get(bytes(request.goal_id.uuid))
            if future is None:  # no such goal (never sent, or expired): its status is unknown, at once
                from action_msgs.msg import GoalStatus

                response = self._action_type.Impl.GetResultService.Response()
                response.status = GoalStatus.STATUS_UNKNOWN
                self.send_result_patiently(header, response)
                return
            future.add_done_callback(functools.partial(self._send_result_response, header))

        def _send_result_response(self, request_header: Any, future: Any) -> None:
            self.send_result_patiently(request_header, future.result())

        def send_result_patiently(self, header: Any, response: Any) -> bool:
            """Send a ``get_result`` response; try again while rmw cannot deliver it. Whether it went out."""
            from rclpy.impl.implementation_singleton import rclpy_implementation

            first, tries = time.monotonic(), 0
            while True:
                tries += 1
                try:
                    if responses.delivered(lambda: self._handle.send_result_response(header, response)):
                        return True
                except rclpy_implementation.RCLError as e:  # e.g. the server is being destroyed: nobody to wait for
                    log.debug("%s: a result response was not sent (%s)", self.sigcore_name, clip(str(e), 200))
                    return False
                if time.monotonic() - first >= responses.GIVE_UP:
                    log.warning("%s: a result response was dropped: the client's response reader was not discovered "
                                "within %g s (%d tries); the client waits in vain", self.sigcore_name,
                                responses.GIVE_UP, tries, extra=log_key(self.sigcore_name, "unsent result"))
                    return False
                time.sleep(responses.RETRY_PERIOD)

    return PatientActionServer
