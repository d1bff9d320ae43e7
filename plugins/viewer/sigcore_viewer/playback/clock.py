"""The playback's clock (``sigcore view DIR``): the moment shown, paused or playing at one of the speeds a person
may pick, seeking within the recording and stopping at its end.
"""

from __future__ import annotations

SPEEDS: dict[str, float] = {"0.25x": 0.25, "0.5x": 0.5, "1x": 1.0, "2x": 2.0, "4x": 4.0, "10x": 10.0}
"""The playback speeds a person may pick (simulated seconds per wall second)."""


class Clock:
    """The playback's time [ns of simulated time] in ``[start, end]``: paused or playing at a speed; it stops at
    the end. Every method takes the wall clock now (``time.perf_counter()``) [s]."""

    def __init__(self, start_ns: int, end_ns: int) -> None:
        self.start_ns, self.end_ns = start_ns, end_ns
        self._t = start_ns
        self._wall = 0.0
        self.playing = False
        self.speed = 1.0

    def now(self, wall: float) -> int:
        """The time at ``wall``; reaching the end pauses there."""
        if self.playing:
            t = self._t + round((wall - self._wall) * self.speed * 1e9)
            if t >= self.end_ns:
                self._t, self.playing = self.end_ns, False
            else:
                return t
        return self._t

    def play(self, wall: float) -> None:
        """Play on from now (from the start when at the end)."""
        t = self.now(wall)
        self._t = self.start_ns if t >= self.end_ns else t
        self._wall = wall
        self.playing = self.end_ns > self.start_ns

    def pause(self, wall: float) -> None:
        self._t = self.now(wall)
        self.playing = False

    def seek(self, t_ns: int, wall: float) -> None:
        """Go to ``t_ns`` (within the recording), playing on from there if playing."""
        self._t = min(max(int(t_ns), self.start_ns), self.end_ns)
        self._wall = wall
        if self._t >= self.end_ns:
            self.playing = False

    def set_speed(self, speed: float, wall: float) -> None:
        self._t = self.now(wall)
        self._wall = wall
        self.speed = speed


def speed_name(speed: float) -> str:
    return next((name for name, value in SPEEDS.items() if value == speed), f"{speed:g}x")
