"""The covariance published with the wheel odometry (``nav_msgs/Odometry``), derived from the wheel model.

Each wheel's speed is taken to be off by a fraction ``σ`` of itself: the odometry's own noise (``noise`` of
:class:`~sigcore.sim.odometry.WheelOdometry`, e.g. the SLAM feature's ``odometry_noise``) or, when it adds none,
:data:`WHEEL_ERROR` (the slip of the simulated wheel contacts). With wheel radius ``r``, separation ``s`` and the
drive's top wheel speed ``ω_max`` (so top body speed ``v_max = r ω_max``), and independent wheel errors:

* pose, over one metre driven straight (``D = 1 m``): ``var(x) = σ² D² / 2``, ``var(yaw) = 2 σ² D² / s²``,
  ``var(y) = D² var(yaw) / 4``;
* twist, at the top speed: ``var(v_x) = var(v_y) = σ² v_max² / 2``, ``var(ω_z) = 2 σ² v_max² / s²``;
* z, roll and pitch (and their rates), which a planar odometry does not measure: :data:`UNOBSERVED`, as
  ros2_control's diff_drive_controller configures them.

The diagonals are constant (like diff_drive_controller's ``pose_covariance_diagonal`` and
``twist_covariance_diagonal``): an upper bound for a robot that drives at most one metre between corrections.
"""

from __future__ import annotations

WHEEL_ERROR = 0.01
"""Relative error of each wheel's speed [fraction] assumed when the odometry adds no noise of its own."""

UNOBSERVED = 1e6
"""Variance of the z, roll and pitch of the pose and of their rates in the twist (not measured by a planar
odometry) [m², rad², (m/s)², (rad/s)²]."""

REFERENCE_DISTANCE = 1.0
"""Distance driven that the pose covariance is given for [m]."""

Diagonal = tuple[float, float, float, float, float, float]
"""A 6x6 covariance's diagonal: x, y, z, roll, pitch, yaw (pose) or v_x, v_y, v_z, ω_x, ω_y, ω_z (twist)."""


def odometry_covariance(radius: float, separation: float, max_wheel_velocity: float,
                        noise: float = 0.0) -> tuple[Diagonal, Diagonal]:
    """The pose and twist covariance diagonals of a differential drive's wheel odometry (formulas above).

    Args:
        radius: Wheel radius [m].
        separation: Distance between the wheels [m].
        max_wheel_velocity: Top wheel speed [rad/s].
        noise: Relative wheel-speed noise of the odometry [fraction]; 0: :data:`WHEEL_ERROR` is used.

    Returns:
        ``(pose, twist)``: the diagonals of the row-major 6x6 ``pose.covariance`` and ``twist.covariance``.
    """
    sigma = noise if noise > 0 else WHEEL_ERROR
    d = REFERENCE_DISTANCE
    var_yaw = 2 * sigma**2 * d**2 / separation**2
    pose = (sigma**2 * d**2 / 2, d**2 * var_yaw / 4, UNOBSERVED, UNOBSERVED, UNOBSERVED, var_yaw)
    v_max = radius * max_wheel_velocity
    var_v = sigma**2 * v_max**2 / 2
    twist = (var_v, var_v, UNOBSERVED, UNOBSERVED, UNOBSERVED, 2 * sigma**2 * v_max**2 / separation**2)
    return pose, twist
