"""Configuration of the ``slam`` feature: the attributes of ``<plugin name="slam" .../>``, validated by the core."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BeforeValidator, Field, model_validator

from sigcore.feature import FeatureConfig
from sigcore.world.exceptions import FieldError


def _pair(value: Any) -> Any:
    if isinstance(value, str):
        parts = value.replace(",", " ").split()
        if len(parts) != 2:
            raise ValueError(f"expected two numbers 'a b', got '{value}'")
        return tuple(parts)
    return value


Pair = Annotated[tuple[float, float], BeforeValidator(_pair)]


class SlamConfig(FeatureConfig):
    """``<plugin name="slam" agent="robot_000" voxel_size="0.2" resolution="0.05" .../>``.

    Every attribute is a string in the world file; numbers and booleans are parsed, unknown attributes are errors
    (the core reports each at its ``file:line:column``).
    """

    agent: str = Field(min_length=1, description="robot whose lidar is mapped; it needs a <drive> and a <lidar>")
    lidar: str = Field(default="", description="name of the robot's <lidar> to use (empty: its first lidar)")
    voxel_size: float = Field(default=0.2, gt=0.0, le=5.0,
                              description="kiss-icp voxel size in [m]; at least twice the point spacing "
                                          "(1 deg beams: 0.15-0.2)")
    max_points_per_voxel: int = Field(default=20, ge=1, le=1000, description="kiss-icp points kept per voxel")
    resolution: float = Field(default=0.05, gt=0.0, le=1.0, description="occupancy grid cell size in [m]")
    size: Pair = Field(default=(30.0, 30.0), description="occupancy grid 'width height' in [m]")
    origin: Pair | None = Field(default=None, description="map-frame 'x y' [m] of the grid's lower-left corner "
                                                          "(default: the grid is centred on the robot's start)")
    odometry_guess: bool = Field(default=True, description="start ICP from the wheel odometry's motion since the "
                                                           "last scan (false: constant-velocity model)")
    refine: bool = Field(default=True, description="refine kiss-icp's pose point-to-line against per-cell line "
                                                   "statistics (cells of voxel_size); false: kiss-icp alone")
    odometry_noise: float = Field(default=0.0, ge=0.0, le=1.0,
                                  description="wheel-speed noise [fraction] if this feature enables the robot's "
                                              "odometry first")
    hit: float = Field(default=0.85, gt=0.0, le=10.0, description="log-odds added to a cell a beam ends in")
    miss: float = Field(default=0.4, gt=0.0, le=10.0, description="log-odds removed from a cell a beam crosses")
    clamp: float = Field(default=5.0, gt=0.0, le=50.0, description="log-odds are kept between -clamp and clamp")

    @model_validator(mode="after")
    def _check(self) -> SlamConfig:
        width, height = self.size
        if width <= 0 or height <= 0:
            raise FieldError("size", f"size '{width:g} {height:g}' must be two positive lengths [m], e.g. '30 30'")
        cells = (width / self.resolution) * (height / self.resolution)
        if cells > 25_000_000:
            raise FieldError("size", f"size '{width:g} {height:g}' at resolution {self.resolution:g} is "
                                     f"{cells:.0f} cells; at most 25000000: use a coarser resolution or a smaller "
                                     "size")
        return self
