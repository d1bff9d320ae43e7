"""Scan-to-map registration of planar scans with kiss-icp (imported when a SLAM feature is created)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from .se2 import Pose2

Array = npt.NDArray[np.float64]


class ScanMatcher:
    """kiss-icp's pipeline on 2D points (z = 0), keeping the estimate on the ground plane.

    kiss-icp predicts each pose as ``last_pose @ last_delta`` (a constant-velocity model); when a motion guess is
    given (e.g. the wheel odometry's motion since the previous scan), it replaces ``last_delta`` for that
    prediction. Deskewing is off: a simulated scan is taken at one instant.

    Args:
        voxel_size: kiss-icp voxel size [m] (the local map's voxels; scans are downsampled at 0.5 and 1.5 times it).
        max_points_per_voxel: Points kept per voxel of the local map.
        min_range: Points closer than this to the origin are dropped [m].
        max_range: Points farther are dropped, and map voxels farther from the robot are forgotten [m].
    """

    def __init__(self, voxel_size: float, max_points_per_voxel: int, min_range: float, max_range: float) -> None:
        from kiss_icp.config import KISSConfig
        from kiss_icp.config.config import AdaptiveThresholdConfig, DataConfig, MappingConfig, RegistrationConfig
        from kiss_icp.kiss_icp import KissICP

        config = KISSConfig(
            data=DataConfig(max_range=max_range, min_range=min_range, deskew=False),
            mapping=MappingConfig(voxel_size=voxel_size, max_points_per_voxel=max_points_per_voxel),
            registration=RegistrationConfig(max_num_threads=1),
            adaptive_threshold=AdaptiveThresholdConfig(initial_threshold=2.0 * voxel_size,
                                                       min_motion_th=voxel_size / 4.0),
        )
        self._icp = KissICP(config)
        self._stamps = np.zeros(0)
        self._previous = Pose2()

    @property
    def pose(self) -> Pose2:
        """The current estimate: the scan frame's pose in the frame of the first scan."""
        return Pose2.from_matrix(self._icp.last_pose)

    def register(self, points: Array, motion: Pose2 | None = None) -> Pose2:
        """Align one scan to the local map, add it to the map, and return the new pose.

        Args:
            points: (n, 2) points [m] in the scan frame.
            motion: Expected motion since the previous scan, in the previous scan frame; ``None``: the
                constant-velocity prediction.
        """
        icp = self._icp
        if motion is not None:
            icp.last_delta = motion.matrix()
        frame = np.zeros((len(points), 3))
        frame[:, :2] = points
        if len(self._stamps) != len(points):
            self._stamps = np.zeros(len(points))
        self._previous = Pose2.from_matrix(icp.last_pose)
        icp.register_frame(frame, self._stamps)
        # keep the estimate planar: the points all lie in z = 0, so any roll, pitch or z is numerical noise
        planar = Pose2.from_matrix(icp.last_pose)
        self.correct(planar)
        return planar

    def correct(self, pose: Pose2) -> None:
        """Replace the latest estimate (e.g. by a refined one); the next prediction starts from it."""
        self._icp.last_pose = pose.matrix()
        self._icp.last_delta = (self._previous.inverse() @ pose).matrix()

    def reset_pose(self, pose: Pose2) -> None:
        """Move the estimate to ``pose`` without registering (a scan with too few points)."""
        self._previous = self.pose
        self.correct(pose)

    def relocate(self, pose: Pose2) -> None:
        """Jump to ``pose`` and forget the motion (the next prediction is "not moving")."""
        self._icp.last_pose = pose.matrix()
        self._icp.last_delta = np.eye(4)
        self._previous = pose
