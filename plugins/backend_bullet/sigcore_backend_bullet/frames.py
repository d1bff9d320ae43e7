"""Pose helpers: sigcore's ``(w, x, y, z)`` quaternions against PyBullet's ``(x, y, z, w)``, and link frames.

PyBullet places a body's base at its *inertial* frame (centre of mass, principal axes as given by the URDF
``<inertial><origin>``); sigcore reports URDF link frames. For the base, ``frame = inertial * inv(local)`` and
``inertial = frame * local``, where ``local`` is the inertial frame in the link frame
(``getDynamicsInfo(...)[3:5]``). Child links need no conversion: ``getLinkState`` returns the URDF link frame
at indices 4 and 5.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
import pybullet as pb

Array = npt.NDArray[np.float64]
Vec = Sequence[float]
Quat = Sequence[float]


def to_wxyz(q: Quat) -> Array:
    """PyBullet ``(x, y, z, w)`` -> sigcore ``(w, x, y, z)``."""
    return np.array([q[3], q[0], q[1], q[2]], dtype=np.float64)


def to_xyzw(q: Array) -> list[float]:
    """sigcore ``(w, x, y, z)`` -> PyBullet ``(x, y, z, w)``, normalised (the core checked it is non-zero)."""
    n = float(np.linalg.norm(q))
    return [float(q[1]) / n, float(q[2]) / n, float(q[3]) / n, float(q[0]) / n]


def compose(pos_a: Vec, orn_a: Quat, pos_b: Vec, orn_b: Quat) -> tuple[Vec, Quat]:
    """``a * b`` of two poses (positions [m], ``(x, y, z, w)`` quaternions)."""
    return pb.multiplyTransforms(pos_a, orn_a, pos_b, orn_b)  # type: ignore[no-any-return]


def invert(pos: Vec, orn: Quat) -> tuple[Vec, Quat]:
    """Inverse of a pose."""
    return pb.invertTransform(pos, orn)  # type: ignore[no-any-return]


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> list[float]:
    """``(x, y, z, w)`` of roll, pitch, yaw [rad] about fixed axes x, y, z (URDF, REP-103)."""
    return list(pb.getQuaternionFromEuler([roll, pitch, yaw]))
