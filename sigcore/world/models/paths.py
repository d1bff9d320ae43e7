"""A person's path (``<path>`` inside a ``<human>``): waypoints to walk through, at a speed, with what the person
waits for at each one (:mod:`sigcore.sim.paths` walks it)."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, model_validator

from ..limits import MAX_COORDINATE
from .base import Name, _Model

MIN_PATH_SPEED = 0.2
"""Slowest walk along a path [m/s] (a stroll; slower, a gait's steps are too short to look like walking)."""
MAX_PATH_SPEED = 1.8
"""Fastest walk along a path [m/s] (a brisk walk: the gait does not run)."""
MAX_WAIT = 3600.0
"""Longest wait at one waypoint [s]."""
MAX_WITHIN = 100.0
"""Largest distance of an ``until_near`` condition [m]."""
MAX_WAYPOINTS = 1000
"""Most waypoints of one path."""
MAX_MESSAGE = 200
"""Longest message text an ``until_message`` waits for [characters]."""

Coordinate = Annotated[float, Field(ge=-MAX_COORDINATE, le=MAX_COORDINATE)]


class Waypoint(_Model):
    """``<waypoint>``: a point a person walks to, and what it waits for there before it walks on: ``wait``
    seconds, then (when given) until ``until_near`` is within ``within`` m and until ``until_message`` came."""

    x: Coordinate = Field(description="where, on the floor, in [m]")
    y: Coordinate = Field(description="where, on the floor, in [m]")
    wait: float = Field(default=0.0, ge=0, le=MAX_WAIT, description="stand this long on arrival in [s]")
    until_near: Name | None = Field(default=None, description="then stand until this entity (a robot, usually) is "
                                                              "within 'within' of the person")
    within: float = Field(default=2.0, gt=0, le=MAX_WITHIN,
                          description="the distance of 'until_near', on the floor, in [m]")
    until_message: str | None = Field(default=None, min_length=1, max_length=MAX_MESSAGE,
                                      description="then stand until the person receives this message text (from "
                                                  "any agent, since it set off toward this waypoint)")

    @model_validator(mode="after")
    def _within_needs_near(self) -> Waypoint:
        if "within" in self.model_fields_set and self.until_near is None:
            raise ValueError("'within' is the distance of 'until_near', which is not given; valid: both, or "
                             "neither")
        return self


class WalkPath(_Model):
    """``<path>``: the waypoints a person walks through, in order, at ``speed``; with ``loop``, back to the first
    after the last, for ever."""

    speed: float = Field(default=1.0, ge=MIN_PATH_SPEED, le=MAX_PATH_SPEED, description="walking speed in [m/s]")
    loop: bool = Field(default=False, description="after the last waypoint, walk to the first and on, for ever")
    waypoints: tuple[Waypoint, ...] = Field(min_length=1, max_length=MAX_WAYPOINTS,
                                            description="where to walk, in order")
