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
    """``rclpy.action.ActionServer`` whose goal and result responses wait for their client, as :mod:`.responses`
    does for services: rclpy sends each response once, and rmw drops it when the client's response reader is not
    discovered yet. On a loaded machine a client sends its goal right after it found the server, and calls
    ``get_result`` right after its goal was accepted, seconds before the server has matched the reader that would
    receive the answer; the client then waits for its acceptance, or its result, forever. Here a send that fails is
    tried again every :data:`~.responses.RETRY_PERIOD` until :data:`~.responses.GIVE_UP` (then a warning names the
    action and the response). The tries block one of the action node's executor threads (:data:`FREE_THREADS` are
    never held by goals).

    An accepted goal runs even if its acceptance could not be delivered: its client asked for it, its result can
    still be asked for, and the goal callback's bookkeeping (one running goal more) is always undone by its end."""

    class PatientActionServer(base):  # type: ignore[valid-type,misc]
        async def _execute_goal_request(self, request_header_and_message: Any) -> None:
            from action_msgs.msg import GoalInfo
            from rclpy.action.server import GoalResponse, ServerGoalHandle
            from rclpy.executors import await_or_execute
            from rclpy.task import Future

            header, request = request_header_and_message
            info = GoalInfo(goal_id=request.goal_id)
            key = bytes(request.goal_id.uuid)
            with self._lock:
                known = self._handle.goal_exists(info)  # the same goal id twice: refused
            handle = None
            if not known and await await_or_execute(self._goal_callback, request.goal) == GoalResponse.ACCEPT:
                info.stamp = self._node.get_clock().now().to_msg()
                try:
                    with self._lock:
                        handle = ServerGoalHandle(self, info, request.goal)
                except RuntimeError as e:  # rcl could not take the goal (e.g. the server is being destroyed)
                    log.warning("%s: an accepted goal could not be started: %s", self.sigcore_name, clip(str(e), 200))
                else:
                    self._goal_handles[key] = handle
                    self._result_futures[key] = Future()
                    self.add_future(self._result_futures[key])
            response = self._action_type.Impl.SendGoalService.Response(accepted=handle is not None, stamp=info.stamp)
            self.send_patiently("goal", lambda: self._handle.send_goal_response(header, response))
            if handle is not None:
                self._handle.publish_status()
                await await_or_execute(self._handle_accepted_callback, handle)

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
            """Send a ``get_result`` response, trying again while rmw cannot deliver it. Whether it went out."""
            return self.send_patiently("result", lambda: self._handle.send_result_response(header, response))

        def send_patiently(self, what: str, send: Any) -> bool:
            """Call ``send`` (of the ``what`` response); again while rmw cannot deliver it. Whether it went out."""
            from rclpy.impl.implementation_singleton import rclpy_implementation

            first, tries = time.monotonic(), 0
            while True:
                tries += 1
                try:
                    if responses.delivered(send):
                        return True
                except rclpy_implementation.RCLError as e:  # e.g. the server is being destroyed: nobody to wait for
                    log.debug("%s: a %s response was not sent (%s)", self.sigcore_name, what, clip(str(e), 200))
                    return False
                if time.monotonic() - first >= responses.GIVE_UP:
                    log.warning("%s: a %s response was dropped: the client's response reader was not discovered "
                                "within %g s (%d tries); the client waits in vain", self.sigcore_name, what,
                                responses.GIVE_UP, tries, extra=log_key(self.sigcore_name, f"unsent {what}"))
                    return False
                time.sleep(responses.RETRY_PERIOD)

    return PatientActionServer
