"""Kinematic chains (arms): declared in the world with ``<arm name base tip>``, or inferred from the grippers."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from .model import RobotModel, Vector


@dataclass(frozen=True)
class Chain:
    """The movable joints from link ``base`` to link ``tip``.

    Attributes:
        name: Arm name (the ``<arm>`` name, or ``left_arm``/``right_arm``/the tip link when inferred).
        base: Link where the chain starts.
        tip: The end-effector link (its URDF frame is what IK places).
        side: ``left``/``right`` when a gripper with that side is the tip, for sig_ros ``arm`` values.
        joints: Movable joint names, base to tip.
        idx_q: Their indices in the full configuration (continuous joints: the cos entry).
        idx_v: Their indices in the full velocity vector.
        lower: Lower limits [rad] or [m], shape ``(n,)`` (-inf for continuous joints).
        upper: Upper limits, shape ``(n,)``.
        tip_frame: Pinocchio frame index of ``tip``.
    """

    name: str
    base: str
    tip: str
    side: str | None
    joints: tuple[str, ...]
    idx_q: tuple[int, ...]
    idx_v: tuple[int, ...]
    lower: Vector
    upper: Vector
    tip_frame: int

    @property
    def direct_q(self) -> bool:
        """No continuous joint: the angles are stored in ``q`` as they are (at ``idx_q``)."""
        return bool(np.all(np.isfinite(self.lower)))

    @property
    def idx_q_array(self) -> npt.NDArray[np.intp]:
        """``idx_q`` as an index array."""
        return np.array(self.idx_q, dtype=np.intp)

    @property
    def dof(self) -> int:
        """Number of joints."""
        return len(self.joints)

    def clamp(self, angles: Vector) -> Vector:
        """``angles`` (shape ``(n,)``) clamped to the limits."""
        return np.clip(angles, self.lower, self.upper)


def build_chain(robot: RobotModel, name: str, base: str, tip: str, side: str | None = None) -> Chain:
    """The chain from ``base`` to ``tip``.

    Raises:
        ValueError: a link is unknown, ``base`` is not an ancestor of ``tip``, or there is no movable joint
            between them (the message lists what would be valid).
    """
    for attr, link in (("base", base), ("tip", tip)):
        if link not in robot.links:
            raise ValueError(f"arm '{name}': {attr} '{link}' is not a link of the URDF; links: "
                             f"{', '.join(robot.links)}")
    joints: list[str] = []
    link = tip
    ancestors = []
    while link != base:
        ancestors.append(link)
        parent, joint = robot.parent_link(link)
        if not parent:
            raise ValueError(f"arm '{name}': base '{base}' is not an ancestor of tip '{tip}'; ancestors of "
                             f"'{tip}': {', '.join(ancestors[1:] + [link]) or 'none'}")
        if joint is not None:
            joints.append(joint)
        link = parent
    joints.reverse()
    if not joints:
        raise ValueError(f"arm '{name}': no movable joint between '{base}' and '{tip}'")
    model = robot.model
    idx_q, idx_v, lower, upper = [], [], [], []
    for j in joints:
        jm = model.joints[robot.joint_id(j)]
        idx_q.append(jm.idx_q)
        idx_v.append(jm.idx_v)
        if jm.nq == 2:  # continuous
            lower.append(-np.inf)
            upper.append(np.inf)
        else:
            lower.append(model.lowerPositionLimit[jm.idx_q])
            upper.append(model.upperPositionLimit[jm.idx_q])
    return Chain(name, base, tip, side, tuple(joints), tuple(idx_q), tuple(idx_v), np.array(lower),
                 np.array(upper), robot.frame_id(tip))


def branch_link(robot: RobotModel, tip: str) -> str:
    """The link where the limb ending at ``tip`` leaves the rest of the robot: walking up from ``tip``, the first
    link with another child subtree that holds a movable joint; the root if there is none."""
    movable_below: dict[str, bool] = {}
    children: dict[str, list[tuple[str, bool]]] = {}
    for link in robot.links:
        parent, joint = robot.parent_link(link)
        if parent:
            children.setdefault(parent, []).append((link, joint is not None))

    def has_movable(link: str) -> bool:
        if link not in movable_below:
            movable_below[link] = any(m or has_movable(c) for c, m in children.get(link, []))
        return movable_below[link]

    child, link = tip, robot.parent_link(tip)[0]
    while link:
        others = [c for c, m in children.get(link, []) if c != child and (m or has_movable(c))]
        if others:
            return link
        child, link = link, robot.parent_link(link)[0]
    return robot.root


def infer_chains(robot: RobotModel, grippers: list[tuple[str, str | None]]) -> list[Chain]:
    """One chain per gripper ``(part, side)``: from the link where its limb branches off to the gripper part.
    Named ``<side>_arm`` when the side is known, else after the part."""
    chains = []
    for part, side in grippers:
        name = f"{side}_arm" if side else part
        chains.append(build_chain(robot, name, branch_link(robot, part), part, side))
    return chains


def chain_angles(robot: RobotModel, chain: Chain, q: Vector) -> Vector:
    """The chain's joint angles in configuration ``q`` (shape ``(n,)``)."""
    return np.array([robot.angle(q, j) for j in chain.joints])


def set_chain_angles(robot: RobotModel, chain: Chain, q: Vector, angles: Vector) -> Vector:
    """A copy of ``q`` with the chain's joints at ``angles``."""
    out = q.copy()
    model = robot.model
    for j, a in zip(chain.joints, angles, strict=True):
        jm = model.joints[robot.joint_id(j)]
        if jm.nq == 2:
            out[jm.idx_q:jm.idx_q + 2] = (np.cos(a), np.sin(a))
        else:
            out[jm.idx_q] = a
    return out


def tip_pose(robot: RobotModel, chain: Chain, q: Vector) -> pin.SE3:
    """Pose of the chain's tip in the root link frame for configuration ``q``."""
    pin.framesForwardKinematics(robot.model, robot.data, q)
    return robot.data.oMf[chain.tip_frame].copy()
