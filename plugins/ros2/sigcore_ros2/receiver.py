"""A background thread that takes incoming ROS 2 messages and requests and queues them for the simulation.

Why not an rclpy executor on the simulation thread: an executor rebuilds its wait set from every entity in
Python on each ``spin_once`` (milliseconds for the hundreds of endpoints of a world), which would cost more than
a physics step. This thread blocks in ``rcl_wait`` (without the GIL) and only wakes on traffic; it never touches
the simulation: it queues ``(callback, message)`` jobs that :meth:`Receiver.drain` runs on the simulation thread
between steps. Service requests are answered later with their request header, so a request whose answer needs
simulated time (step N, a deferred API call) holds nothing but its header.

Endpoints come and go while running (agents spawned and deleted): each thread rebuilds its wait set when the set of
endpoints changed, and :meth:`Receiver.retire` waits until both threads let go of an endpoint before it may be
destroyed, answering its queued requests first.

Every service added gets a :class:`~sigcore_ros2.responses.Responder` behind its ``send_response``: a response
whose client is not discovered yet is kept and sent again between steps instead of being dropped by rmw.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable, Collection
from typing import Any

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription

from sigcore.api.call import log_key
from sigcore.text import clip

from .responses import Responder

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
        self._queue_lock = threading.Lock()  # appends from the threads vs. removing the jobs of retired endpoints
        self._arrived = threading.Event()
        self.responder = Responder()
        """Sends the services' responses; retries those whose client is not matched yet (see responses.py)."""
        self._drained = threading.Event()
        self._stop = False
        self._threads: list[threading.Thread] = []
        self._version = 0  # bumped when endpoints are added or retired: the threads rebuild their wait sets
        self._seen = [0, 0]  # the version each thread (services, topics) waits with
        self._changed = threading.Condition()
        with context.handle:
            self._wakes = [_rclpy.GuardCondition(context.handle), _rclpy.GuardCondition(context.handle)]

    def add_subscription(self, sub: Subscription, callback: Callable[[Any], None]) -> None:
        """``callback(msg)`` will run on the simulation thread for each message (before or after :meth:`start`)."""
        with self._changed:
            self._subs.append((sub, callback))
            self._version += 1
        self._wakes[1].trigger_guard_condition()

    def add_service(self, srv: Any, callback: Callable[[Any, Any], None]) -> None:
        """``callback(request, header)`` will run on the simulation thread; it answers with
        ``srv.send_response(response, header)``, now or after later steps (before or after :meth:`start`)."""
        self.responder.install(srv)
        with self._changed:
            self._srvs.append((srv, callback))
            self._version += 1
        self._wakes[0].trigger_guard_condition()

    def retire(self, entities: Collection[Any], refuse: Callable[[Any, Any, Any], None] | None = None,
               timeout: float = 5.0) -> bool:
        """Stop waiting on ``entities`` (subscriptions and services; simulation thread), so that they can be
        destroyed: waits (at most ``timeout`` [s]) until both threads wait without them, then takes their queued
        jobs out of the queue: a queued request of a service is handed to ``refuse(srv, request, header)`` (which
        answers it), a queued message is dropped.

        Returns:
            Whether the threads let go of them within ``timeout`` (only then may they be destroyed).
        """
        gone = {id(e) for e in entities}
        with self._changed:
            self._subs = [(s, cb) for s, cb in self._subs if id(s) not in gone]
            self._srvs = [(s, cb) for s, cb in self._srvs if id(s) not in gone]
            self._version += 1
            version = self._version
        for wake in self._wakes:
            wake.trigger_guard_condition()
        running = [i for i, t in enumerate(self._threads) if t.is_alive()]
        with self._changed:
            released = self._changed.wait_for(lambda: all(self._seen[i] >= version for i in running), timeout)
        with self._queue_lock:
            jobs = list(self._queue)
            kept = [j for j in jobs if not (isinstance(j, _Job) and id(j.entity) in gone)]
            if len(kept) != len(jobs):
                self._queue.clear()
                self._queue.extend(kept)
        for job in jobs:
            if isinstance(job, _Job) and id(job.entity) in gone and len(job.args) == 2 and refuse is not None:
                try:
                    refuse(job.entity, *job.args)
                except Exception as e:  # answering a held request must not stop the simulation
                    _failed(job.endpoint, "refusing a request of a retired endpoint", e)
        if not released:
            log.error("the ROS 2 receiver threads did not let go of %d retired endpoints within %g s; they are "
                      "kept (not destroyed)", len(gone), timeout)
        return released

    @property
    def pending(self) -> bool:
        """Whether jobs wait for :meth:`drain`, or a kept response is due (cheap: checked every step)."""
        return bool(self._queue) or self.responder.due

    def start(self) -> None:
        """Start two threads: one waits on the services, one on the subscriptions (a wait's cost grows with the
        number of entities, and requests should not pay for the hundreds of command topics)."""
        self._threads = [
            threading.Thread(target=self._run, args=(0,), name="sigcore-ros2-services", daemon=True),
            threading.Thread(target=self._run, args=(1,), name="sigcore-ros2-topics", daemon=True)]
        for thread in self._threads:
            thread.start()

    def stop(self) -> None:
        """Stop the threads (each returns within a wait)."""
        self._stop = True
        for wake in self._wakes:
            wake.trigger_guard_condition()
        for thread in self._threads:
            thread.join(timeout=5.0)

    def submit(self, job: Job) -> None:
        """Queue ``job()`` for the simulation thread (from any thread)."""
        with self._queue_lock:
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
            except Exception as e:  # a bug in one callback must not stop the simulation
                endpoint = getattr(job, "endpoint", "a queued job")
                kind = type(e).__name__
                log.error("ROS 2 callback of %s failed (%s: %s)", endpoint, kind, clip(str(e), 200),
                          exc_info=True, extra=log_key(endpoint, kind))
        self._drained.set()
        self.responder.retry()

    def _run(self, which: int) -> None:
        """The loop of thread ``which`` (0: services, 1: subscriptions); its wait set is rebuilt whenever endpoints
        were added or retired."""
        version = -1
        wait_set: Any = None
        sub_handles: list[Any] = []
        srv_handles: list[Any] = []
        subs: dict[int, tuple[Subscription, Callable[[Any], None], str]] = {}
        srvs: dict[int, tuple[Any, Callable[[Any, Any], None]]] = {}
        while not self._stop and self._context.ok():
            try:
                if version != self._version:
                    with self._changed:
                        version = self._version
                        sub_list = list(self._subs) if which == 1 else []
                        srv_list = list(self._srvs) if which == 0 else []
                    subs = {s.handle.pointer: (s, cb, s.topic_name) for s, cb in sub_list}
                    srvs = {s.handle.pointer: (s, cb) for s, cb in srv_list}
                    with self._context.handle:
                        wait_set = _rclpy.WaitSet(len(subs), 1, 0, 0, len(srvs), 0, self._context.handle)
                    sub_handles = [s.handle for s, _ in sub_list]
                    srv_handles = [s.handle for s, _ in srv_list]
                    with self._changed:
                        self._seen[which] = version  # this thread no longer holds the retired endpoints
                        self._changed.notify_all()
                if not self._wait_once(which, wait_set, sub_handles, srv_handles, subs, srvs):
                    break
            except Exception as e:  # a bug here must not end the thread: every later request would hang
                kind = type(e).__name__
                name = threading.current_thread().name
                log.error("the ROS 2 receiver thread %s failed (%s: %s); still serving", name, kind,
                          clip(str(e), 200), exc_info=True, extra=log_key(name, kind))
                time.sleep(0.01)  # a failure that repeats must not spin a core
        with self._changed:
            self._seen[which] = 1 << 62  # ended: holds nothing
            self._changed.notify_all()

    def _wait_once(self, which: int, wait_set: Any, sub_handles: list[Any], srv_handles: list[Any],
                   subs: dict[int, tuple[Subscription, Callable[[Any], None], str]],
                   srvs: dict[int, tuple[Any, Callable[[Any, Any], None]]]) -> bool:
        """Wait for traffic and queue it; False when the thread must end."""
        queue, arrived, drained = self._queue, self._arrived, self._drained
        wait_set.clear_entities()  # about 0.3 ms with the GIL for 700 endpoints: done while nothing waits
        add = wait_set.add_subscription
        for handle in sub_handles:
            add(handle)
        add = wait_set.add_service
        for handle in srv_handles:
            add(handle)
        wait_set.add_guard_condition(self._wakes[which])
        try:
            wait_set.wait(-1)
        except Exception:  # the context was shut down under us
            return False
        if self._stop:
            return False
        jobs: list[Job] = []
        for ptr in wait_set.get_ready_entities("subscription"):
            sub, cb, topic = subs[ptr]
            while True:
                try:
                    with sub.handle:
                        taken = sub.handle.take_message(sub.msg_type, False)
                except Exception as e:  # e.g. a message that cannot be deserialized: dropped
                    _failed(topic, "taking a message", e)
                    taken = None
                if taken is None:
                    break
                jobs.append(_Job(cb, (taken[0],), topic, sub))
        for ptr in wait_set.get_ready_entities("service"):
            srv, scb = srvs[ptr]
            while True:
                try:
                    with srv.handle:
                        request, header = srv.handle.service_take_request(srv.srv_type.Request)
                except Exception as e:  # a request that cannot be deserialized: dropped
                    _failed(srv.srv_name, "taking a request", e)
                    header = None
                if header is None:
                    break
                jobs.append(_Job(scb, (request, header), srv.srv_name, srv))
        if jobs:
            with self._queue_lock:
                queue.extend(jobs)
            drained.clear()
            arrived.set()
            # let the simulation thread take the GIL and answer at its next step boundary before this
            # thread rebuilds its wait set (bounded: the simulation may be busy in a long step)
            drained.wait(0.002)
        return True


class _Job:
    """``callback(*args)`` for the simulation thread, with the endpoint it came from (for the log)."""

    __slots__ = ("args", "callback", "endpoint", "entity")

    def __init__(self, callback: Callable[..., None], args: tuple[Any, ...], endpoint: str, entity: Any) -> None:
        self.callback, self.args, self.endpoint, self.entity = callback, args, endpoint, entity

    def __call__(self) -> None:
        self.callback(*self.args)


def _failed(endpoint: str, what: str, e: Exception) -> None:
    kind = type(e).__name__
    log.error("%s: %s failed (%s: %s); dropped", endpoint, what, kind, clip(str(e), 200),
              extra=log_key(endpoint, kind))
