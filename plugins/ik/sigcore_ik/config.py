"""Configuration of the ``ik`` feature: the attributes of ``<plugin name="ik" .../>``, validated by the core."""

from __future__ import annotations

from typing import Annotated

from pydantic import BeforeValidator, Field

from sigcore.feature import FeatureConfig


def _names(value: object) -> object:
    return tuple(value.replace(",", " ").split()) if isinstance(value, str) else value


Names = Annotated[tuple[str, ...], BeforeValidator(_names)]
"""Names separated by spaces or commas (``"robot_000 robot_001"``)."""


class IkConfig(FeatureConfig):
    """``<plugin name="ik" agent="robot_000" max_joint_speed="1.0"/>``; every attribute is optional."""

    agent: Names = Field(default=(), description="robots with IK, separated by spaces (default: every robot)")
    max_joint_speed: float = Field(default=1.0, gt=0.0, le=100.0,
                                   description="peak joint speed of a move in [rad/s]")
