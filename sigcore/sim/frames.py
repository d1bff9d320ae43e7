"""Frame names and the static transforms of a world: one owner for the TF tree's fixed part.

Frames follow REP-105: with one robot, ``odom`` and the URDF's link names (``base_link``); with several, each robot's
frames are prefixed with ``<robot>/``. The static part of the tree is ``world -> odom`` for every robot with a
``<drive>`` (its start pose) and every fixed joint of every robot's URDF. A feature may re-parent a robot's ``odom``
(SLAM: ``world -> map`` static, ``map -> odom`` on ``/tf``): each child frame has exactly one parent here, so the
tree keeps one root. Published by the core on ``/tf_static`` (latched) through the publication contract.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..geometry import quat_conj, quat_mul, quat_rotate, quat_yaw
from ..publish import Publication, Publisher, planar_quaternion, transform_fields

if TYPE_CHECKING:
    from .simulation import Simulation

WORLD = "world"
"""The root frame: the world file's frame."""

TF_STATIC = Publication("/tf_static", "tf2_msgs/msg/TFMessage", "latched",
                        "the fixed part of the TF tree: world -> odom per robot, every fixed joint")


class Frames:
    """Frame names and the static transforms ``child -> (parent, translation [m], rotation (w, x, y, z))``.

    Args:
        sim: The simulation (its backend must be built: fixed joints are read from the initial link poses).
    """

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        robots = [a.name for a in sim.world.agents if a.kind == "robot"]
        self._prefix = {r: (f"{r}/" if len(robots) > 1 else "") for r in robots}
        self._static: dict[str, tuple[str, tuple[float, ...], tuple[float, ...]]] = {}
        self._publisher: Publisher | None = None  # declared once the constructor has filled the tree
        for robot in robots:
            if sim.robot_model(robot).drive is not None:
                pos, quat = sim.backend.get_pose(robot)
                self.set_static(WORLD, self.name(robot, "odom"), (pos[0], pos[1], 0.0),
                                planar_quaternion(quat_yaw(quat)))
            self._fixed_joints(robot)
        self._publisher = sim.publications.declare(TF_STATIC)
        self.publish()

    def _fixed_joints(self, robot: str) -> None:
        sim, urdf = self._sim, self._sim.urdf(robot)
        for joint in urdf.joints:
            if joint.movable:
                continue
            try:
                pp, pq = sim.backend.get_pose(robot, None if joint.parent == urdf.root else joint.parent)
                cp, cq = sim.backend.get_pose(robot, None if joint.child == urdf.root else joint.child)
            except Exception:  # a link the backend merged away (no body of its own)
                continue
            inv = quat_conj(pq)
            self.set_static(self.name(robot, joint.parent), self.name(robot, joint.child),
                            quat_rotate(inv, np.asarray(cp) - np.asarray(pp)), quat_mul(inv, cq))

    # ------------------------------------------------------------------ names
    def prefix(self, robot: str) -> str:
        """``""`` with one robot, ``"<robot>/"`` with several."""
        return self._prefix[robot]

    def name(self, robot: str, frame: str) -> str:
        """The TF name of ``robot``'s frame ``frame`` (a link, ``odom``, ``map``)."""
        return self._prefix[robot] + frame

    # ------------------------------------------------------------------ the static tree
    def set_static(self, parent: str, child: str, xyz: Any, wxyz: Any) -> None:
        """Fix ``parent -> child`` (replacing ``child``'s previous parent); republished if already published."""
        self._static[child] = (parent, tuple(float(v) for v in xyz), tuple(float(v) for v in wxyz))
        self._republish()

    def remove_static(self, child: str) -> None:
        """Drop the static transform to ``child`` (another publisher gives it a parent, e.g. on ``/tf``)."""
        if self._static.pop(child, None) is not None:
            self._republish()

    def static(self) -> dict[str, tuple[str, tuple[float, ...], tuple[float, ...]]]:
        """``child -> (parent, xyz, wxyz)`` of every static transform."""
        return dict(self._static)

    def static_fields(self, stamp_ns: int) -> dict[str, Any]:
        """The ``tf2_msgs/TFMessage`` fields of every static transform, stamped ``stamp_ns`` [ns]."""
        return {"transforms": [transform_fields(parent, child, stamp_ns, xyz, wxyz)
                               for child, (parent, xyz, wxyz) in self._static.items()]}

    def publish(self) -> None:
        """Push the static tree on ``/tf_static`` (latched: done at construction and whenever it changes)."""
        assert self._publisher is not None
        self._publisher.publish(self.static_fields(self._sim.stamp_ns))

    def _republish(self) -> None:
        if self._publisher is not None:
            self.publish()
