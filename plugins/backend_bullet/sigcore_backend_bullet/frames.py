"""Pose helpers: sigcore's ``(w, x, y, z)`` quaternions against PyBullet's ``(x, y, z, w)``, and link frames.

PyBullet places a body's base at its *inertial* frame (centre of mass, principal axes as given by the URDF
``<inertial><origin>``); sigcore reports URDF link frames. For the base, ``frame = inertial * inv(local)`` and
``inertial = frame * local``, where ``local`` is the inertial frame in the link frame
(``getDynamicsInfo(...)[3:5]``). Child links need no conversion: ``getLinkState`` returns the URDF link frame
at indices 4 and 5.

Poses are composed here in double precision: PyBullet's ``multiplyTransforms`` and ``invertTransform`` round to
single precision (0.599 comes back as 0.59899997...).
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


_ORIGIN = (0.0, 0.0, 0.0)
_IDENTITY = (0.0, 0.0, 0.0, 1.0)


def compose(pos_a: Vec, orn_a: Quat, pos_b: Vec, orn_b: Quat) -> tuple[Vec, Quat]:
    """``a * b`` of two poses (positions [m], ``(x, y, z, w)`` quaternions)."""
    if tuple(pos_b) == _ORIGIN and tuple(orn_b) == _IDENTITY:
        return tuple(float(v) for v in pos_a), tuple(float(v) for v in orn_a)
    ax, ay, az, aw = (float(v) for v in orn_a)
    bx, by, bz, bw = (float(v) for v in orn_b)
    rx, ry, rz = _rotate(ax, ay, az, aw, *(float(v) for v in pos_b))
    return ((float(pos_a[0]) + rx, float(pos_a[1]) + ry, float(pos_a[2]) + rz),
            (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
             aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz))


def invert(pos: Vec, orn: Quat) -> tuple[Vec, Quat]:
    """Inverse of a pose."""
    x, y, z, w = (-float(orn[0]), -float(orn[1]), -float(orn[2]), float(orn[3]))
    px, py, pz = _rotate(x, y, z, w, *(float(v) for v in pos))
    return (-px, -py, -pz), (x, y, z, w)


def _rotate(x: float, y: float, z: float, w: float, vx: float, vy: float, vz: float) -> tuple[float, float, float]:
    """``v`` rotated by the unit quaternion ``(x, y, z, w)``: ``v + 2 w (u x v) + 2 u x (u x v)``."""
    tx, ty, tz = 2.0 * (y * vz - z * vy), 2.0 * (z * vx - x * vz), 2.0 * (x * vy - y * vx)
    return (vx + w * tx + y * tz - z * ty, vy + w * ty + z * tx - x * tz, vz + w * tz + x * ty - y * tx)


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> list[float]:
    """``(x, y, z, w)`` of roll, pitch, yaw [rad] about fixed axes x, y, z (URDF, REP-103)."""
    return list(pb.getQuaternionFromEuler([roll, pitch, yaw]))
