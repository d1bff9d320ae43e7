"""How many steps the core may let the backend take in one call (:meth:`sigcore.backend.Backend.step_batch`).

Between two steps the core has work only when something is due: a lidar scan, a camera image, a controller's
``on_action``, a ``step`` subscriber (each says how often with ``every``, :mod:`.events`), an odometry (every step),
a camera image in flight (polled every step), a queued message or force (delivered before the next step). Contact
events need no stop of their own: the backend stops after a step whose contacts changed. Up to the first step after
which something is due, the steps are free: :func:`free_steps` counts them and the backend takes them at once.
"""

from __future__ import annotations

from .camera import Cameras
from .events import Events
from .population import Entities

BATCH_STEPS = 1000
"""The most steps the backend takes in one call (a signal or another thread waits at most that long: about 50 ms
on MuJoCo)."""


def free_steps(entities: Entities, cameras: Cameras, events: Events, step: int, n: int) -> int:
    """After step ``step``, how many of the next ``n`` steps may be taken in one call: up to and including the first
    one after which something is due, at most :data:`BATCH_STEPS`; 1 while something needs every step."""
    if entities.odometry or cameras.in_flight:
        return 1
    free = events.steps_free(step, min(n, BATCH_STEPS))
    for lidar in entities.lidars:
        free = min(free, lidar.period_steps - step % lidar.period_steps)
    if cameras.every:
        free = min(free, cameras.every - step % cameras.every)
    due = entities.controllers.next_action
    if due is not None:
        free = min(free, max(1, due - step))
    return free
