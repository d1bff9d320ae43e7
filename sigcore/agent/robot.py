"""Robot handle: joints, differential drive and grasping, on top of :class:`~sigcore.agent.handle.SimObj`."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from ..backend import MAIN, Array
from ..geometry import angle_about, quat_conj, quat_mul
from ..text import quote
from .exceptions import ApiError, GraspError, GraspRefusal
from .handle import SimObj, _num, _vec


class RobotObj(SimObj):
    """Handle of a robot: everything of :class:`SimObj` plus joints, wheels and grippers."""

    # ------------------------------------------------------------------ joints
    def joint_names(self) -> list[str]:
        """Movable joint names."""
        return self.sim.backend.joints(self.name)

    def _joint(self, joint: str) -> str:
        joints = self.sim.backend.joints(self.name)
        if joint not in joints:
            raise ApiError(f"'{self.name}' has no joint {quote(joint)}; joints: {', '.join(joints) or 'none'}")
        return joint

    def joint_angle(self, joint: str) -> float:
        """Joint position [rad] (or [m] for prismatic joints)."""
        return self.sim.backend.get_joint_angle(self.name, self._joint(joint))

    def all_joint_angles(self) -> dict[str, float]:
        """Every movable joint's position, by name."""
        return {j: self.sim.backend.get_joint_angle(self.name, j) for j in self.joint_names()}

    def set_joint_angle(self, joint: str, angle: float) -> None:
        """Set a joint position instantly (kinematic); its servo then holds it. Limits are enforced.

        SIGVerse allowed this only with dynamics off; sigcore allows it in both modes.
        """
        j = self._joint(joint)
        a = _num(angle, "angle [rad]", low=-1e3, high=1e3)
        self._check_limits(j, a)
        self.sim.backend.set_joint_angle(self.name, j, a)

    def set_joint_target(self, joint: str, angle: float) -> None:
        """Move a joint to ``angle`` [rad] through its position servo (over time, with the world's gains)."""
        j = self._joint(joint)
        a = _num(angle, "angle [rad]", low=-1e3, high=1e3)
        self._check_limits(j, a)
        self.sim.backend.set_joint_target(self.name, j, a)

    def set_joint_quaternion(self, joint: str, wxyz: Iterable[float], offset: bool = False) -> None:
        """Set a 1-DoF revolute joint from a rotation quaternion about its axis (instant, like set_joint_angle).

        Args:
            joint: Joint name.
            wxyz: Rotation (w, x, y, z) in the joint frame; its component about the joint axis is used.
            offset: Add the rotation to the current angle instead of replacing it.
        """
        j = self._joint(joint)
        q = _vec(wxyz, "quaternion (qw qx qy qz)", 4)
        n = float(np.linalg.norm(q))
        if n < 1e-9:
            raise ApiError("quaternion must be non-zero, e.g. 1 0 0 0")
        urdf_joint = self.sim.entities.urdf(self.name).joint(j)
        if urdf_joint.type == "prismatic":
            raise ApiError(f"joint '{j}' is prismatic; set_joint_quaternion needs a revolute joint")
        angle = angle_about(urdf_joint.axis, q)
        if offset:
            angle += self.joint_angle(j)
        self.set_joint_angle(j, angle)

    def joint_velocity(self, joint: str) -> float:
        """Joint velocity [rad/s]."""
        return self.sim.backend.get_joint_velocity(self.name, self._joint(joint))

    def set_joint_velocity(self, joint: str, velocity: float, max_torque: float | None = None) -> None:
        """Drive a joint at ``velocity`` [rad/s] with at most ``max_torque`` [N m] (None or <= 0: default)."""
        j = self._joint(joint)
        v = _num(velocity, "angular velocity [rad/s]", low=-1e3, high=1e3)
        mt = None if max_torque is None else _num(max_torque, "max torque [N m]")
        self.sim.backend.set_joint_velocity(self.name, j, v, mt if mt is not None and mt > 0 else None)

    def add_joint_torque(self, joint: str, torque: float) -> None:
        """Add a torque [N m] on a joint for the next step (needs dynamics on)."""
        j = self._joint(joint)
        self._dynamic("add_joint_torque")
        self.sim.backend.add_joint_torque(self.name, j, _num(torque, "torque [N m]", low=-1e5, high=1e5))

    def joint_position(self, joint: str) -> Array:
        """World position [m] of a joint's anchor."""
        return self.sim.backend.get_joint_position(self.name, self._joint(joint))

    def _check_limits(self, joint: str, angle: float) -> None:
        uj = self.sim.entities.urdf(self.name).joint(joint)
        if uj.lower is not None and uj.upper is not None and not uj.lower - 1e-9 <= angle <= uj.upper + 1e-9:
            raise ApiError(f"angle {angle} is outside the limits of '{joint}': [{uj.lower}, {uj.upper}]")

    # ------------------------------------------------------------------ differential drive
    def wheel_geometry(self) -> tuple[float, float]:
        """``(radius, separation)`` [m] of the differential drive now in use."""
        return self.sim.entities.drive(self.name).geometry()

    def set_wheel(self, radius: float, separation: float) -> None:
        """Set the drive geometry (sig_ros ``setWheel``): wheel ``radius`` and ``separation`` [m].

        From now on :meth:`set_base_velocity` (``cmd_vel``) and the wheel odometry use it; ``Simulation.reset``
        restores the world file's ``<drive>``. The physical wheels stay the URDF's.

        Raises:
            ApiError: the robot has no ``<drive>``, or a value is not a finite number in ``(0, 5]`` (radius) or
                ``(0, 20]`` (separation) [m].
        """
        self.sim.entities.drive(self.name).set_geometry(radius, separation)

    def set_wheel_velocity(self, left: float, right: float) -> None:
        """Set the wheel speeds [rad/s]; positive on both drives forward. Speeds beyond the drive's
        ``max_wheel_velocity`` are refused. The wheel joints turn at these speeds whatever the geometry set by
        :meth:`set_wheel`; the odometry turns them into a body velocity with that geometry."""
        drive = self.sim.entities.drive(self.name)
        lim = drive.max_wheel_velocity
        lv = _num(left, "left wheel velocity [rad/s]", low=-lim, high=lim)
        rv = _num(right, "right wheel velocity [rad/s]", low=-lim, high=lim)
        self.sim.backend.set_joint_velocity(self.name, drive.left, lv, drive.max_torque)
        self.sim.backend.set_joint_velocity(self.name, drive.right, rv, drive.max_torque)

    def set_base_velocity(self, linear: float, angular: float) -> None:
        """Drive with a body velocity: ``linear`` [m/s] forward and ``angular`` [rad/s] about z (cmd_vel), turned
        into wheel speeds with the drive geometry now in use (:meth:`set_wheel`)."""
        drive = self.sim.entities.drive(self.name)
        v = _num(linear, "linear velocity [m/s]")
        w = _num(angular, "angular velocity [rad/s]")
        self.set_wheel_velocity(*drive.wheel_speeds(v, w))

    # ------------------------------------------------------------------ grasping
    def grippers(self) -> list[str]:
        """Parts that can grasp."""
        return [g.part for g in self.sim.entities.robot_model(self.name).grippers]

    def grasp(self, part: str, obj: str) -> None:
        """Grasp object ``obj`` with gripper ``part``.

        Raises:
            GraspError: refused, with SIGVerse's reasons: unknown part or object, part not a gripper, part already
                grasping, object held by another, object not graspable, object beyond the grasp radius.
        """
        model = self.sim.entities.robot_model(self.name)
        grippers = {g.part: g for g in model.grippers}
        if part not in self.sim.backend.parts(self.name):
            raise GraspError(GraspRefusal.UNKNOWN_PART, f"'{self.name}' has no part {quote(part)}; grippers: "
                             f"{', '.join(grippers) or 'none'}")
        if part not in grippers:
            raise GraspError(GraspRefusal.NOT_A_GRIPPER, f"part {quote(part)} is not a gripper; grippers: "
                             f"{', '.join(grippers) or 'none'}")
        if obj not in self.sim.entities.names or obj == self.name:
            raise GraspError(GraspRefusal.UNKNOWN_OBJECT, f"no object {quote(obj)}; graspable objects: "
                             f"{', '.join(self.sim.entities.graspable) or 'none'}")
        grasps = self.sim.entities.grasps
        held = grasps.holding(self.name, part)
        if held is not None:
            raise GraspError(GraspRefusal.ALREADY_GRASPING, f"'{part}' already holds '{held}'; release it first")
        holder_part = grasps.held_by(obj)
        if holder_part is not None:
            holder, hpart = holder_part
            raise GraspError(GraspRefusal.HELD_BY_ANOTHER, f"'{obj}' is held by {holder}/{hpart}")
        if obj not in self.sim.entities.graspable:
            raise GraspError(GraspRefusal.NOT_GRASPABLE, f"'{obj}' is not graspable (graspable=\"true\" in the "
                             f"world file); graspable objects: {', '.join(self.sim.entities.graspable) or 'none'}")
        hand = self.sim.backend.get_pose(self.name, part)[0]
        target = self.sim.backend.get_com(obj)
        dist = float(np.linalg.norm(target - hand))
        radius = grippers[part].grasp_radius
        if dist > radius:
            raise GraspError(GraspRefusal.TOO_FAR, f"'{obj}' is {dist:.3f} m from '{part}', beyond the grasp "
                             f"radius {radius} m")
        self.sim.backend.attach(self.name, part, obj)
        grasps.hold(self.name, part, obj)

    def release(self, part: str) -> str | None:
        """Release what ``part`` holds; returns the released object's name, or None if it held nothing."""
        if part not in self.grippers():
            raise ApiError(f"part {quote(part)} is not a gripper of '{self.name}'; grippers: "
                           f"{', '.join(self.grippers()) or 'none'}")
        obj = self.sim.entities.grasps.release(self.name, part)
        if obj is not None:
            self.sim.backend.detach(self.name, part, obj)
        return obj

    def gripper_for_arm(self, arm: str) -> str:
        """Gripper part for a sig_ros ``arm`` value: a gripper part name, or ``left``/``right`` (by ``side``)."""
        grippers = self.sim.entities.robot_model(self.name).grippers
        for g in grippers:
            if arm in (g.part, g.side):
                return g.part
        valid = [g.part for g in grippers] + [g.side for g in grippers if g.side]
        raise ApiError(f"no gripper {quote(arm)} on '{self.name}'; valid: {', '.join(valid) or 'none'}")

    def relative_rotation(self, part: str) -> Array:
        """Orientation of ``part`` relative to the main part (w, x, y, z)."""
        q_main = self.rotation()
        q_part = self.part_rotation(part)
        return quat_mul(quat_conj(q_main), q_part)


__all__ = ["MAIN", "RobotObj"]
