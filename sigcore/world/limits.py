"""The largest numbers a world file may hold where a model's own range does not bound them: positions, angles, sizes
and ranges (``docs/world-format.md``, "Limits"). Each is far beyond any real scene, and far below what overflows
what the engines and sigcore compute from it (a square, a volume, an inertia): ``1e308`` passes ``float()`` but not
these.
"""

from __future__ import annotations

import math

__all__ = ["MAX_ANGLE", "MAX_COORDINATE", "MAX_LIDAR_RANGE", "MAX_SIZE", "check_magnitudes", "parse_floats"]

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


def parse_floats(text: str, count: int | None = None, valid: str = "", expected: str = "") -> tuple[float, ...]:
    """The finite numbers of ``text``, separated by spaces (``count`` of them when given): the one reader of such
    attributes in world files, URDFs and feature configurations.

    Args:
        text: The attribute's text.
        count: How many numbers there must be (None: any).
        valid: What is valid, appended to each message as ``; valid: ...``.
        expected: Words after ``expected N numbers`` (e.g. `` 'x0 y0 z0 x1 y1 z1'``).

    Raises:
        ValueError: not numbers, not ``count`` of them, or not finite; the message quotes ``text``.
    """
    tail = f"; valid: {valid}" if valid else ""
    try:
        numbers = tuple(float(p) for p in text.split())
    except ValueError:
        raise ValueError(f"{text!r} is not numbers separated by spaces{tail}") from None
    if count is not None and len(numbers) != count:
        raise ValueError(f"expected {count} numbers{expected}, got {len(numbers)} ({text!r}){tail}")
    if not all(math.isfinite(n) for n in numbers):
        raise ValueError(f"numbers must be finite, got {text!r}{tail}")
    return numbers
