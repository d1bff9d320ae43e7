"""A background thread that takes incoming ROS 2 messages and requests and queues them for the simulation.

Why not an rclpy executor on the simulation thread: an executor rebuilds its wait set from every entity in
Python on each ``spin_once`` (milliseconds for the hundreds of endpoints of a world), which would cost more than
a physics step. This thread blocks in ``rcl_wait`` (without the GIL) and only wakes on traffic; it never touches
the simulation: it queues ``(callback, message)`` jobs that :meth:`Receiver.drain` runs on the simulation thread
between steps. Service requests are answered later with their request header, so a request whose answer needs
simulated time (step N, a deferred API call) holds nothing but its header.
"""

from __future__ import annotations

import logging
import threading
from collections import deque
from collections.abc import Callable
from typing import Any

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription

log = logging.getLogger("sigcore.ros2")

Job = Callable[[], None]


class Receiver:
    """Waits on subscriptions and services in a daemon thread; :meth:`drain` runs their callbacks.

    Args:
        context: The rclpy context of the node.
    """

    def __init__(self, context: Any) -> None:
        self._context = context
        self._subs: list[tuple[Subscription, Callable[[Any], None]]] = []
        self._srvs: list[tuple[Any, Callable[[Any, Any], None]]] = []
        self._queue: deque[Job] = deque()
        self._arrived = threading.Event()
        self._drained = threading.Event()
        self._stop = False
        self._threads: list[threading.Thread] = []
        with context.handle:
            self._wake = _rclpy.GuardCondition(context.handle)

    def add_subscription(self, sub: Subscription, callback: Callable[[Any], None]) -> None:
        """``callback(msg)`` will run on the simulation thread for each message (before :meth:`start`)."""
        self._subs.append((sub, callback))

    def add_service(self, srv: Any, callback: Callable[[Any, Any], None]) -> None:
        """``callback(request, header)`` will run on the simulation thread; it answers with
        ``srv.send_response(response, header)``, now or after later steps (before :meth:`start`)."""
        self._srvs.append((srv, callback))

    @property
    def pending(self) -> bool:
        """Whether jobs wait for :meth:`drain` (cheap: checked every step)."""
        return bool(self._queue)

    def start(self) -> None:
        """Start two threads: one waits on the services, one on the subscriptions (a wait's cost grows with the
        number of entities, and requests should not pay for the hundreds of command topics)."""
        self._threads = [
            threading.Thread(target=self._run, args=([], self._srvs), name="sigcore-ros2-services", daemon=True),
            threading.Thread(target=self._run, args=(self._subs, []), name="sigcore-ros2-topics", daemon=True)]
        for thread in self._threads:
            thread.start()

    def stop(self) -> None:
        """Stop the threads (each returns within a wait)."""
        self._stop = True
        self._wake.trigger_guard_condition()
        for thread in self._threads:
            thread.join(timeout=5.0)

    def submit(self, job: Job) -> None:
        """Queue ``job()`` for the simulation thread (from any thread)."""
        self._queue.append(job)
        self._arrived.set()

    def wait(self, timeout: float) -> None:
        """Block up to ``timeout`` [s] until a job arrives (used while the simulation is paused)."""
        if not self._queue and timeout > 0:
            self._arrived.wait(timeout)
        self._arrived.clear()

    def drain(self) -> None:
        """Run every queued job, in arrival order (simulation thread only)."""
        queue = self._queue
        while queue:
            job = queue.popleft()
            try:
                job()
            except Exception:  # a bug in one callback must not stop the simulation
                log.exception("ROS 2 callback failed")
        self._drained.set()

    def _run(self, sub_list: list[tuple[Subscription, Callable[[Any], None]]],
             srv_list: list[tuple[Any, Callable[[Any, Any], None]]]) -> None:
        subs = {s.handle.pointer: (s, cb) for s, cb in sub_list}
        srvs = {s.handle.pointer: (s, cb) for s, cb in srv_list}
        with self._context.handle:
            wait_set = _rclpy.WaitSet(len(subs), 1, 0, 0, len(srvs), 0, self._context.handle)
        sub_handles = [s.handle for s, _ in sub_list]
        srv_handles = [s.handle for s, _ in srv_list]
        queue, arrived, drained = self._queue, self._arrived, self._drained
        while not self._stop and self._context.ok():
            wait_set.clear_entities()  # about 0.3 ms with the GIL for 700 endpoints: done while nothing waits
            add = wait_set.add_subscription
            for handle in sub_handles:
                add(handle)
            add = wait_set.add_service
            for handle in srv_handles:
                add(handle)
            wait_set.add_guard_condition(self._wake)
            try:
                wait_set.wait(-1)
            except Exception:  # the context was shut down under us
                break
            if self._stop:
                self._wake.trigger_guard_condition()  # the other thread too
                break
            for ptr in wait_set.get_ready_entities("subscription"):
                sub, cb = subs[ptr]
                while True:
                    try:
                        with sub.handle:
                            taken = sub.handle.take_message(sub.msg_type, False)
                    except Exception:
                        taken = None
                    if taken is None:
                        break
                    queue.append(_bind1(cb, taken[0]))
            for ptr in wait_set.get_ready_entities("service"):
                srv, scb = srvs[ptr]
                while True:
                    try:
                        with srv.handle:
                            request, header = srv.handle.service_take_request(srv.srv_type.Request)
                    except Exception:
                        header = None
                    if header is None:
                        break
                    queue.append(_bind2(scb, request, header))
            if queue:
                drained.clear()
                arrived.set()
                # let the simulation thread take the GIL and answer at its next step boundary before this
                # thread rebuilds its wait set (bounded: the simulation may be busy in a long step)
                drained.wait(0.002)


def _bind1(cb: Callable[[Any], None], a: Any) -> Job:
    return lambda: cb(a)


def _bind2(cb: Callable[[Any, Any], None], a: Any, b: Any) -> Job:
    return lambda: cb(a, b)
