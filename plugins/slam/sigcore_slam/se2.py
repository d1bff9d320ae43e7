"""Planar rigid transforms (SE(2)): the poses SLAM keeps and hands to transports."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Pose2:
    """A planar transform ``a_T_b``: frame ``b``'s origin and heading expressed in frame ``a``.

    Attributes:
        x: [m].
        y: [m].
        yaw: [rad] about z, in (-pi, pi].
    """

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    def __matmul__(self, other: Pose2) -> Pose2:
        """Composition ``a_T_b @ b_T_c = a_T_c``."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return Pose2(self.x + c * other.x - s * other.y, self.y + s * other.x + c * other.y,
                     wrap(self.yaw + other.yaw))

    def inverse(self) -> Pose2:
        """``b_T_a`` from ``a_T_b``."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return Pose2(-c * self.x - s * self.y, s * self.x - c * self.y, wrap(-self.yaw))

    def apply(self, points: Array) -> Array:
        """Map (n, 2) points [m] from frame ``b`` into frame ``a``."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        out = np.empty_like(points)
        out[:, 0] = c * points[:, 0] - s * points[:, 1] + self.x
        out[:, 1] = s * points[:, 0] + c * points[:, 1] + self.y
        return out

    def matrix(self) -> Array:
        """The (4, 4) homogeneous transform (z = 0, rotation about z)."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        m = np.eye(4)
        m[0, 0], m[0, 1], m[1, 0], m[1, 1] = c, -s, s, c
        m[0, 3], m[1, 3] = self.x, self.y
        return m

    @classmethod
    def from_matrix(cls, m: Array) -> Pose2:
        """Project a (4, 4) transform onto the ground plane (x, y and the heading of its x axis)."""
        return cls(float(m[0, 3]), float(m[1, 3]), math.atan2(float(m[1, 0]), float(m[0, 0])))

    def quaternion(self) -> tuple[float, float, float, float]:
        """The rotation as a quaternion (w, x, y, z), for ``geometry_msgs/Transform``."""
        return (math.cos(self.yaw / 2), 0.0, 0.0, math.sin(self.yaw / 2))


def wrap(angle: float) -> float:
    """``angle`` [rad] wrapped into (-pi, pi]."""
    return math.atan2(math.sin(angle), math.cos(angle))
