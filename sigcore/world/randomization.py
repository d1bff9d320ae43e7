"""``<randomize>``: what a seeded run draws, as strict models (``docs/world-format.md``, "<randomize>").

Only the element's own rules live here: numbers, ranges, which attributes go together. The checks against the world
(entity names, surfaces, named areas, bounds) are :func:`sigcore.world.randomize.check`'s, the drawing is
:func:`sigcore.world.randomize.sample`'s. This module imports nothing of :mod:`sigcore.world.models`, which holds a
:class:`Randomize` in its ``World``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, field_validator, model_validator

from .exceptions import FieldError
from .limits import MAX_ANGLE, MAX_COORDINATE, check_magnitudes, parse_floats

DEFAULT_ATTEMPTS = 200
"""Draws per entity before :func:`sigcore.world.randomize.sample` gives up."""

DEFAULT_CLEARANCE = 0.02
"""Default gap between a drawn entity's footprint and the others' [m]."""


def _numbers(count: int, help_: str, limit: float, unit: str, what: str) -> BeforeValidator:
    """Split ``"a b c"`` into ``count`` finite floats within ``±limit`` [``unit``] (``what`` they are); the message
    says what was expected (``help_``)."""

    def parse(value: object) -> object:
        if not isinstance(value, str):
            return value
        numbers = parse_floats(value, count, help_)
        check_magnitudes(numbers, limit, unit, what)
        return numbers

    return BeforeValidator(parse)


def _words(value: object) -> object:
    return tuple(value.split()) if isinstance(value, str) else value


_REGION_HELP = "'x0 y0 x1 y1' [m] with x0 <= x1 and y0 <= y1"
_YAW_HELP = "'lo hi' [rad] with lo <= hi"

Region = Annotated[tuple[float, float, float, float], _numbers(4, _REGION_HELP, MAX_COORDINATE, "m", "coordinates")]
YawRange = Annotated[tuple[float, float], _numbers(2, _YAW_HELP, MAX_ANGLE, "rad", "angles")]
Names = Annotated[tuple[str, ...], BeforeValidator(_words)]


class Located(BaseModel):
    """Strict and frozen, with where its element is in the file (for the messages of later checks); also the base of
    ``<plugin>``'s model."""

    model_config = ConfigDict(extra="forbid", frozen=True, str_strip_whitespace=True, allow_inf_nan=False)

    line: int = 0
    column: int = 0
    positions: dict[str, tuple[int, int]] = Field(default_factory=dict,
                                                  description="(line, column) of each attribute, for messages")

    def location(self, attribute: str | None = None) -> tuple[int, int]:
        """``(line, column)`` of attribute ``attribute`` (of the element if ``None`` or absent)."""
        return self.positions.get(attribute or "", (self.line, self.column))


class RandomPose(Located):
    """``<pose>`` in ``<randomize>``: where an entity's position (and yaw) is drawn."""

    entity: str = Field(description="the robot, object or human to place")
    region: Region | None = Field(default=None, description="'x0 y0 x1 y1': the box in world its position is drawn "
                                                            "in [m]")
    on: Names | None = Field(default=None, description="entities whose top face it is put on (one drawn per try)")
    area: str | None = Field(default=None, description="a <named_pose> with bounds: its x/y box is the region")
    z: float | None = Field(default=None, ge=-MAX_COORDINATE, le=MAX_COORDINATE,
                            description="height of its position in [m]; default: the file's (not with 'on')")
    yaw: YawRange | None = Field(default=None, description="'lo hi': its yaw is drawn in this range [rad]; default: "
                                                           "the file's orientation")
    clearance: float = Field(default=DEFAULT_CLEARANCE, ge=0, le=10,
                             description="least gap between its footprint and the others' in [m]")

    @field_validator("region")
    @classmethod
    def _region(cls, v: tuple[float, float, float, float] | None) -> tuple[float, float, float, float] | None:
        if v is not None and not (v[0] <= v[2] and v[1] <= v[3]):
            got = " ".join(f"{c:g}" for c in v)
            raise ValueError(f"{got} is an empty region (x0 > x1 or y0 > y1); valid: {_REGION_HELP}")
        return v

    @field_validator("yaw")
    @classmethod
    def _yaw(cls, v: tuple[float, float] | None) -> tuple[float, float] | None:
        if v is not None and v[0] > v[1]:
            raise ValueError(f"{v[0]:g} > {v[1]:g} is an empty range; valid: {_YAW_HELP}, e.g. '-3.1416 3.1416'")
        return v

    @field_validator("on")
    @classmethod
    def _on(cls, v: tuple[str, ...] | None) -> tuple[str, ...] | None:
        if v is not None:
            if not v:
                raise ValueError("names no entity; valid: one or more entity names separated by spaces")
            twice = next((name for i, name in enumerate(v) if name in v[:i]), None)
            if twice is not None:
                raise ValueError(f"'{twice}' is named twice; valid: each surface once")
        return v

    @model_validator(mode="after")
    def _where(self) -> RandomPose:
        given = [k for k in ("region", "on", "area") if getattr(self, k) is not None]
        if not given:
            raise ValueError("no place to draw from; valid: one of 'region' (x0 y0 x1 y1), 'on' (surface entities, "
                             "optionally with 'region') or 'area' (a named pose with bounds)")
        if self.area is not None and len(given) > 1:
            other = next(k for k in given if k != "area")
            raise FieldError("area", f"'{other}' and 'area' are both given; valid: 'region', 'on' (optionally with "
                                     "'region') or 'area'")
        if self.on is not None and self.z is not None:
            raise FieldError("z", "'z' is drawn from the surface with 'on' (its top plus the entity's bottom); valid: "
                                  "'z' with 'region' or 'area' only")
        return self


class Option(Located):
    """``<option>`` in ``<choose>``: one variant of the object; its attributes replace the object's."""

    attributes: dict[str, str] = Field(default_factory=dict,
                                       description="<object> attributes (all but 'name') as written")
    weight: float = Field(default=1.0, gt=0, le=1e6, description="relative chance of being picked")


class Choice(Located):
    """``<choose>`` in ``<randomize>``: one of its options is picked for the object."""

    entity: str = Field(description="the <object> whose variants these are")
    options: tuple[Option, ...] = ()

    @model_validator(mode="after")
    def _some(self) -> Choice:
        if not self.options:
            raise ValueError("<choose> holds no <option>; valid: one or more <option .../> elements")
        return self


GEOMETRY = ("shape", "size", "mesh", "urdf", "scale")
"""An object's geometry attributes: an option that gives ``shape``, ``mesh`` or ``urdf`` replaces them all."""


def with_option(attributes: Mapping[str, object], option: Mapping[str, str]) -> dict[str, object]:
    """An object's ``attributes`` as an ``<option>`` changes them: each attribute the option gives replaces the
    object's; when it gives ``shape``, ``mesh`` or ``urdf``, the object's whole geometry (:data:`GEOMETRY`) goes
    first, so an option may turn a cylinder into a mesh."""
    new_geometry = any(key in option for key in ("shape", "mesh", "urdf"))
    kept = {k: v for k, v in attributes.items() if not (new_geometry and k in GEOMETRY)}
    return {**kept, **option}


class Randomize(Located):
    """``<randomize>``: the poses and models a seeded run draws (:func:`sigcore.world.randomize.sample`)."""

    attempts: int = Field(default=DEFAULT_ATTEMPTS, ge=1, le=100000,
                          description="draws per entity before giving up")
    poses: tuple[RandomPose, ...] = ()
    choices: tuple[Choice, ...] = ()

    @property
    def entities(self) -> tuple[str, ...]:
        """The entities it changes (those of ``<choose>``, then those of ``<pose>``), each once."""
        out: list[str] = []
        for name in [c.entity for c in self.choices] + [p.entity for p in self.poses]:
            if name not in out:
                out.append(name)
        return tuple(out)
