"""How long an evaluation has left: its episodes run ``workers`` at once, so the time left is that of the running
episodes' ends and of the queued ones, ``workers`` at a time (not the wall time per episode ended times the episodes
left, which counts each episode as if it ran alone)."""

from __future__ import annotations

import heapq
import time
from collections.abc import Callable


class Eta:
    """The wall time left of an evaluation, from the mean wall time of the episodes ended so far.

    Episodes are taken to start as soon as a worker is free: ``min(workers, todo)`` at the start, then one as each
    ends. A running episode is taken to need the mean wall time in all (none if it already ran longer); each queued
    one starts on the first worker free and takes the mean.

    Args:
        todo: Episodes to run.
        workers: Episodes at once (>= 1).
        clock: Wall clock [s] (``time.monotonic``).
    """

    def __init__(self, todo: int, workers: int, clock: Callable[[], float] = time.monotonic) -> None:
        self.clock = clock
        self.workers = max(1, workers)
        now = clock()
        self.running: list[float] = [now] * min(self.workers, todo)
        """The start times of the running episodes [s, of ``clock``]."""
        self.queued = todo - len(self.running)
        self.walls: list[float] = []

    def set_workers(self, workers: int) -> None:
        """There are ``workers`` now (a Ray cluster, once its CPUs are known): queued episodes start on the new ones."""
        self.workers = max(1, workers)
        now = self.clock()
        while self.queued > 0 and len(self.running) < self.workers:
            self.queued -= 1
            self.running.append(now)

    def ended(self, wall_time: float) -> None:
        """An episode ended after ``wall_time`` [s]; the next queued one starts on its worker."""
        now = self.clock()
        if self.running:
            started = now - wall_time
            self.running.pop(min(range(len(self.running)), key=lambda i: abs(self.running[i] - started)))
        self.walls.append(wall_time)
        if self.queued > 0:
            self.queued -= 1
            self.running.append(now)

    def left(self) -> float | None:
        """Wall time until the last episode ends [s]; None before one has ended, 0 when none is left."""
        if not self.running and not self.queued:
            return 0.0
        if not self.walls:
            return None
        mean = sum(self.walls) / len(self.walls)
        now = self.clock()
        free = [max(mean - (now - start), 0.0) for start in self.running]
        free += [0.0] * max(0, self.workers - len(free))
        heapq.heapify(free)
        for _ in range(self.queued):
            heapq.heappush(free, heapq.heappop(free) + mean)
        return max(free)
