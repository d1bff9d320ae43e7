"""Quaternion helpers for the MuJoCo backend. Quaternions are ``(w, x, y, z)``, as in MuJoCo and sigcore."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

Array = npt.NDArray[np.float64]


def quat_from_rpy(roll: float, pitch: float, yaw: float) -> Array:
    """Quaternion of roll (x), pitch (y), yaw (z) [rad] about fixed axes, applied in that order (URDF,
    REP-103).

    Returns:
        (4,) unit quaternion ``Rz(yaw) * Ry(pitch) * Rx(roll)``.
    """
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return np.array([
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    ])


def quat_mul(a: Array, b: Array) -> Array:
    """Hamilton product ``a * b`` of two (4,) quaternions."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array([
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    ])


def quat_conj(q: Array) -> Array:
    """Inverse of a (4,) unit quaternion."""
    return np.array([q[0], -q[1], -q[2], -q[3]])


def quat_to_matrix(q: Array) -> Array:
    """(3, 3) rotation matrix of a (4,) unit quaternion."""
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def unit(q: Array) -> Array:
    """``q`` scaled to unit length (the core has checked it is non-zero and finite)."""
    q = np.asarray(q, dtype=np.float64)
    return q / float(np.linalg.norm(q))
