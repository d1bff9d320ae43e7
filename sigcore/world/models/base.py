"""Building blocks shared by every world model: the strict, frozen base model, the field types that parse XML
attribute strings (``Vec*`` numbers, names, tags, descriptions), :class:`Pose`, and the entity-name rule.
"""

from __future__ import annotations

import math
import re
from typing import Annotated

from pydantic import AfterValidator, BaseModel, BeforeValidator, ConfigDict, Field

from ..limits import MAX_ANGLE, MAX_COORDINATE, check_magnitudes, parse_floats

NAME_PATTERN = r"^[A-Za-z][A-Za-z0-9_]*$"
"""Entity names become ROS 2 topic names (``<agent>_setPosition``): a letter, then letters, digits, ``_``."""


def _numbers(count: int | None) -> BeforeValidator:
    def parse(value: object) -> object:
        if isinstance(value, str):
            return parse_floats(value, count)
        if isinstance(value, tuple | list):
            if count is not None and len(value) != count:
                raise ValueError(f"expected {count} numbers, got {len(value)}")
            for v in value:
                if isinstance(v, float) and not math.isfinite(v):
                    raise ValueError(f"numbers must be finite, got {v}")
        return value

    return BeforeValidator(parse)

Vec3 = Annotated[tuple[float, float, float], _numbers(3)]
Vec4 = Annotated[tuple[float, float, float, float], _numbers(4)]
Vec6 = Annotated[tuple[float, float, float, float, float, float], _numbers(6)]
Floats = Annotated[tuple[float, ...], _numbers(None)]
Name = Annotated[str, Field(pattern=NAME_PATTERN, max_length=64)]
Tags = Annotated[tuple[str, ...], BeforeValidator(lambda v: tuple(v.split()) if isinstance(v, str) else v)]

MAX_TAGS = 64
"""Most tags one entity or named pose may carry."""

MAX_TAG_LENGTH = 64
"""Longest tag [characters]."""

MAX_DESCRIPTION = 1000
"""Longest description of an entity or named pose [characters]."""


def check_tags(tags: tuple[str, ...]) -> tuple[str, ...]:
    """``tags`` if each is a non-empty printable word without whitespace, at most :data:`MAX_TAG_LENGTH`
    characters, and there are at most :data:`MAX_TAGS` of them.

    Raises:
        ValueError: naming the first tag that breaks a rule and the rule.
    """
    if len(tags) > MAX_TAGS:
        raise ValueError(f"{len(tags)} tags; valid: at most {MAX_TAGS}")
    for tag in tags:
        if not isinstance(tag, str) or not tag:
            raise ValueError(f"tag {tag!r} is empty or not text; valid: non-empty words")
        if len(tag) > MAX_TAG_LENGTH:
            raise ValueError(f"tag {tag[:20]!r}... has {len(tag)} characters; valid: at most {MAX_TAG_LENGTH}")
        if any(c.isspace() for c in tag) or not tag.isprintable():
            raise ValueError(f"tag {tag[:40]!r} holds whitespace or control characters; valid: one printable word "
                             "per tag")
    return tags


def check_description(text: str) -> str:
    """``text`` if it has at most :data:`MAX_DESCRIPTION` characters.

    Raises:
        ValueError: it is longer.
    """
    if len(text) > MAX_DESCRIPTION:
        raise ValueError(f"description of {len(text)} characters; valid: at most {MAX_DESCRIPTION}")
    return text


EntityTags = Annotated[Tags, AfterValidator(check_tags)]
Description = Annotated[str, AfterValidator(check_description)]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, str_strip_whitespace=True, allow_inf_nan=False)


class Pose(_Model):
    """A pose: position [m] and roll/pitch/yaw [rad] (fixed axes x, y, z)."""

    xyz: Vec3 = (0.0, 0.0, 0.0)
    rpy: Vec3 = (0.0, 0.0, 0.0)

    @classmethod
    def parse(cls, value: object) -> object:
        """Accept ``"x y z roll pitch yaw"`` or ``"x y z"``."""
        if isinstance(value, str):
            parts = value.split()
            if len(parts) not in (3, 6):
                raise ValueError(f"expected 3 or 6 numbers, got {len(parts)} ({value!r}); "
                                 "valid: 'x y z' or 'x y z roll pitch yaw'")
            try:
                numbers = [float(p) for p in parts]
            except ValueError:
                raise ValueError(f"{value!r} is not numbers separated by spaces") from None
            if not all(math.isfinite(n) for n in numbers):
                raise ValueError(f"numbers must be finite, got {value!r}")
            check_magnitudes(tuple(numbers[:3]), MAX_COORDINATE, "m", "x, y, z")
            check_magnitudes(tuple(numbers[3:]), MAX_ANGLE, "rad", "roll, pitch, yaw")
            rpy = (numbers[3], numbers[4], numbers[5]) if len(numbers) == 6 else (0.0, 0.0, 0.0)
            return cls(xyz=(numbers[0], numbers[1], numbers[2]), rpy=rpy)
        return value


PoseField = Annotated[Pose, BeforeValidator(Pose.parse)]


def valid_name(name: str) -> bool:
    """Whether ``name`` is a valid entity name."""
    return re.fullmatch(NAME_PATTERN, name) is not None
