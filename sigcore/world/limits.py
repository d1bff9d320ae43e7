"""The largest numbers a world file may hold where a model's own range does not bound them: positions, angles, sizes
and ranges (``docs/world-format.md``, "Limits"). Each is far beyond any real scene, and far below what overflows
what the engines and sigcore compute from it (a square, a volume, an inertia): ``1e308`` passes ``float()`` but not
these.
"""

from __future__ import annotations

__all__ = ["MAX_ANGLE", "MAX_COORDINATE", "MAX_LIDAR_RANGE", "MAX_SIZE", "check_magnitudes"]

MAX_COORDINATE = 10_000.0
"""Largest coordinate of a position in a world file [m] (poses, named poses' bounds, ``<randomize>`` regions): a
world 20 km across. Beyond it the engines lose precision (and ``1e308`` overflows what they compute from it)."""

MAX_ANGLE = 100.0
"""Largest angle of a pose in a world file [rad] (about 16 turns; angles repeat every 2π)."""

MAX_SIZE = 1000.0
"""Largest size of a primitive shape [m] (a side, a radius, a length)."""

MAX_LIDAR_RANGE = 1000.0
"""Largest ``max`` of a lidar's ``range`` [m] (long-range scanners reach a few hundred metres)."""


def check_magnitudes(numbers: tuple[float, ...], limit: float, unit: str, what: str = "numbers") -> None:
    """Refuse a number beyond ``±limit``.

    Raises:
        ValueError: naming the first such number and the valid range.
    """
    big = next((n for n in numbers if abs(n) > limit), None)
    if big is not None:
        raise ValueError(f"{big:g} is out of range; valid: {what} from {-limit:g} to {limit:g} [{unit}]")
