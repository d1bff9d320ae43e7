"""The ``<plugin name="referee" .../>`` attributes, as a strict pydantic model (validated by the core)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BeforeValidator, Field, field_validator

from sigcore.feature import FeatureConfig
from sigcore.world.limits import parse_floats


def _words(value: object) -> object:
    return tuple(value.split()) if isinstance(value, str) else value


def _corners(value: object) -> object:
    if not isinstance(value, str):
        return value
    numbers = parse_floats(value, 6, expected=" 'x0 y0 z0 x1 y1 z1'")
    if not all(numbers[i] < numbers[i + 3] for i in range(3)):
        raise ValueError("the corners must satisfy x0 < x1, y0 < y1, z0 < z1")
    return numbers


Words = Annotated[tuple[str, ...], BeforeValidator(_words)]
Corners = Annotated[tuple[float, float, float, float, float, float] | None, BeforeValidator(_corners)]


class RefereeConfig(FeatureConfig):
    """Attributes of ``<plugin name="referee">``; every one is optional. Points are integers."""

    rules: Literal["cleanup", "none"] = Field(
        default="none", description="built-in rules: 'cleanup' detects the clean-up task's events itself; "
                                    "'none' only scores the messages of the viewer service")
    service: str = Field(default="referee", min_length=1,
                         description="name of the viewer service (_connect_to_service, _send_msg_to_srv)")
    correct_box: int = Field(default=1000, description="trash item at rest in a box that accepts it [points]")
    wrong_box: int = Field(default=-600, description="trash item at rest in another trash box [points]")
    grasp: int = Field(default=50, description="first grasp of each trash item [points]")
    collision: int = Field(default=-100, description="one contact episode of a robot with furniture, a wall "
                                                     "or the floor [points]")
    time_limit: float = Field(default=600.0, ge=0, description="the task ends this long after the start in "
                                                               "[s]; 0: no limit")
    debounce: float = Field(default=0.5, gt=0, le=60, description="a contact episode ends after no contact "
                                                                  "for this long in [s]")
    rest_speed: float = Field(default=0.05, gt=0, le=10, description="an item below this speed is at rest in "
                                                                     "[m/s]")
    rest_time: float = Field(default=0.5, ge=0, le=60, description="an item must stay at rest this long before "
                                                                   "it is judged in [s]")
    rate: float = Field(default=10.0, gt=0, le=1000, description="how often the rules look at the world in "
                                                                 "[Hz] (collisions are seen every step)")
    trash_tag: str = Field(default="trash", min_length=1, description="tag of the trash items")
    box_tag: str = Field(default="trashbox", min_length=1, description="tag of the trash boxes")
    collision_tags: Words = Field(default=("furniture", "wall"), description="a robot touching an entity with "
                                                                             "one of these tags is penalised")
    floor: bool = Field(default=True, description="penalise robot parts other than floor_parts touching the "
                                                  "ground")
    floor_parts: Words | None = Field(default=None, description="robot parts allowed on the ground; default: "
                                                                "the drive's wheel links and links named "
                                                                "*caster*")
    robots: Words | None = Field(default=None, description="robots the rules watch; default: every robot")
    box_inner: Corners = Field(default=None, description="inner volume of every trash box, two corners in the "
                                                         "box's frame in [m]; default: read from its URDF")
    stop_on_finish: bool = Field(default=False, description="stop the run when the task ends")

    @field_validator("service")
    @classmethod
    def _one_word(cls, value: str) -> str:
        if any(c.isspace() for c in value):
            raise ValueError(f"{value!r} has spaces; valid: one word, e.g. 'referee'")
        return value
