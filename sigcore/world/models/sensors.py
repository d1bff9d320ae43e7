"""The sensors a robot carries: ``<lidar>`` (a planar laser scanner) and ``<camera>`` (a pinhole camera)."""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import BeforeValidator, Field, field_validator, model_validator

from ..exceptions import FieldError
from ..limits import MAX_LIDAR_RANGE
from .base import Name, Pose, PoseField, _Model, _numbers

_FULL_TURN_SLACK = 1e-3
"""``fov`` values up to 2π + this [rad] are taken as 2π, so that ``fov="6.2832"`` means a full turn."""


def _full_turn(value: object) -> object:
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return value  # pydantic reports it
    return 2 * math.pi if 2 * math.pi < number <= 2 * math.pi + _FULL_TURN_SLACK else value


class Lidar(_Model):
    """``<lidar>``: a planar laser scanner on one link, rays in the link's x-y plane, counter-clockwise."""

    name: Name = Field(description="scanner name, unique within the robot")
    link: str = Field(description="URDF link the scanner sits on")
    beams: int = Field(default=360, ge=1, le=10000, description="rays per scan")
    fov: Annotated[float, BeforeValidator(_full_turn)] = Field(
        default=2 * math.pi, gt=0, le=2 * math.pi,
        description="field of view in [rad] (up to 2π + 0.001 means 2π)",
    )
    range: Annotated[tuple[float, float], _numbers(2)] = Field(
        default=(0.05, 10.0), description="'min max' distance in [m]"
    )
    rate: float = Field(default=10.0, gt=0, le=1000, description="scans per simulated second in [Hz]")
    noise: float = Field(default=0.0, ge=0, le=1, description="Gaussian range noise std-dev in [m]")

    @field_validator("range")
    @classmethod
    def _range(cls, v: tuple[float, float]) -> tuple[float, float]:
        if not 0 <= v[0] < v[1] <= MAX_LIDAR_RANGE:
            raise ValueError(f"min {v[0]:g} and max {v[1]:g} do not satisfy 0 <= min < max <= "
                             f"{MAX_LIDAR_RANGE:g}; valid: 'min max' [m], e.g. '0.05 10'")
        return v


CameraKind = Literal["rgb", "depth", "rgbd"]


class Camera(_Model):
    """``<camera>``: a pinhole camera on one link (square pixels). Its body frame follows REP-103 (x forward, y left,
    z up) at ``pose`` in the link's frame; images are published in its optical frame (z forward, x right, y down)."""

    name: Name = Field(description="camera name, unique within the robot; names its topics and frames")
    link: str = Field(description="URDF link the camera sits on")
    pose: PoseField = Field(default=Pose(), description="'x y z' [m] or 'x y z roll pitch yaw' [m, rad] in the "
                                                        "link's frame; the camera looks along its x")
    width: int = Field(default=320, ge=8, le=4096, description="image width in [px]")
    height: int = Field(default=240, ge=8, le=4096, description="image height in [px]")
    fov: float = Field(default=math.pi / 3, gt=0.01, lt=3.14,
                       description="horizontal field of view in [rad] (ignored when 'focal' is given)")
    focal: float | None = Field(default=None, gt=0, le=1e5, description="focal length in [px] (fx = fy)")
    principal: Annotated[tuple[float, float], _numbers(2)] | None = Field(
        default=None, description="'cx cy' principal point in [px]; default: the image centre, "
                                  "((width - 1) / 2, (height - 1) / 2)")
    near: float = Field(default=0.05, gt=0, le=100, description="nearest distance rendered in [m]")
    far: float = Field(default=10.0, gt=0, le=10000, description="farthest distance rendered in [m]; depth beyond "
                                                                 "it (or no hit) is +inf")
    rate: float = Field(default=15.0, gt=0, le=1000, description="images per simulated second in [Hz]")
    type: CameraKind = Field(default="rgbd", description="what it renders: rgb, depth or rgbd (both)")
    noise: float = Field(default=0.0, ge=0, le=1, description="Gaussian depth noise std-dev in [m]")

    @model_validator(mode="after")
    def _check(self) -> Camera:
        if self.near >= self.far:
            raise ValueError(f"near {self.near:g} must be less than far {self.far:g}; valid: e.g. near='0.05' "
                             "far='10'")
        if self.principal is not None:
            cx, cy = self.principal
            if not (0 <= cx <= self.width - 1 and 0 <= cy <= self.height - 1):
                raise FieldError("principal", f"principal point ({cx:g}, {cy:g}) lies outside the "
                                              f"{self.width}x{self.height} image; valid: 0 <= cx <= "
                                              f"{self.width - 1}, 0 <= cy <= {self.height - 1}")
        return self

    @property
    def intrinsics(self) -> tuple[float, float, float]:
        """``(f, cx, cy)`` [px]: the focal length and the principal point (pixel centres at integers)."""
        f = self.focal if self.focal is not None else (self.width / 2) / math.tan(self.fov / 2)
        cx, cy = self.principal if self.principal is not None else ((self.width - 1) / 2, (self.height - 1) / 2)
        return f, cx, cy

    @property
    def link_frame(self) -> str:
        """The camera's body frame (x forward), a child of :attr:`link` (unprefixed)."""
        return f"{self.name}_link"

    @property
    def optical_frame(self) -> str:
        """The camera's optical frame (z forward, x right), a child of :attr:`link_frame` (unprefixed)."""
        return f"{self.name}_optical_frame"
