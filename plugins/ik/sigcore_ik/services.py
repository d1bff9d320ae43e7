"""The IK services: sig_ros ``_ik`` and the typed ``_ik_solve``, as API entries for robots."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin

from sigcore.agent.exceptions import ApiError
from sigcore.api.table import ROBOT, ApiEntry

from . import types as t
from .exceptions import InvalidTargetError
from .feature import MOVE_TOLERANCE, IkFeature, finite
from .robot import se3

if TYPE_CHECKING:
    from sigcore.api.deferred import Deferred
    from sigcore.sim import Simulation

DEFAULT_TOLERANCE = 1e-4
"""Position tolerance of ``_ik`` and of ``_ik_solve`` with ``tolerance`` 0 [m]."""
MAX_TIMEOUT = 600.0
"""Longest move timeout a request may ask for [s]."""


def _feature(sim: Simulation) -> IkFeature:
    feature = sim.features.get("ik")
    if not isinstance(feature, IkFeature):
        raise ApiError('IK is not enabled in this world; add <plugin name="ik"/> to the world file')
    return feature


def ik(sim: Simulation, agent: str, req: Any) -> Deferred:
    """sig_ros ``_ik``: move the hand of arm ``req.arm`` to a point (position only), answer ``done`` once there."""
    f = _feature(sim)
    r = f.robot(agent)
    chain = r.chain(req.arm)
    point = np.array([finite(req.x, "x"), finite(req.y, "y"), finite(req.z, "z")])
    base = r.base_pose()
    if req.position == "absolute":
        world = point
    elif req.position == "relative":
        world = base.act(point)
    else:
        world = base.act(f.default_tip(agent, chain) + point)
    target = pin.SE3(np.eye(3), world)
    result = f.solve(agent, chain, target, True, DEFAULT_TOLERANCE)
    return f.move(agent, chain, result.angles, target, None, {"done": True}, None)


def ik_solve(sim: Simulation, agent: str, req: Any) -> dict[str, Any] | Deferred:
    """``_ik_solve``: solve for a pose target in a named frame, optionally move there and measure the error."""
    f = _feature(sim)
    r = f.robot(agent)
    chain = r.chain(req.chain)
    position = np.array([finite(req.x, "x"), finite(req.y, "y"), finite(req.z, "z")])
    quat = np.array([finite(req.qw, "qw"), finite(req.qx, "qx"), finite(req.qy, "qy"), finite(req.qz, "qz")])
    tolerance = finite(req.tolerance, "tolerance") or DEFAULT_TOLERANCE
    timeout = finite(req.timeout, "timeout") or None
    if not 1e-7 <= tolerance <= 0.1:
        raise InvalidTargetError(f"tolerance is {tolerance} m; valid: 1e-7 .. 0.1 [m], or 0 for the default "
                                 f"{DEFAULT_TOLERANCE:g}")
    if timeout is not None and not 0 < timeout <= MAX_TIMEOUT:
        raise InvalidTargetError(f"timeout is {timeout} s; valid: (0, {MAX_TIMEOUT:g}] [s], or 0 for the move's "
                                 "duration plus 5 s")
    norm = float(np.linalg.norm(quat))
    position_only = req.position_only or norm == 0.0
    if not position_only and norm < 1e-6:
        raise InvalidTargetError(f"quaternion norm is {norm:g}; valid: a unit quaternion (w, x, y, z), or all 0 "
                                 "(or position_only) for a position-only target")
    local = se3(position, quat) if not position_only else pin.SE3(np.eye(3), position)
    target = r.frame_pose(req.frame).act(local)
    result = f.solve(agent, chain, target, position_only, tolerance)
    answer: dict[str, Any] = {"joint_names": list(chain.joints), "joint_positions": [float(a) for a in result.angles],
                              "solver_error": result.position_error}
    if not req.move:
        return {**answer, "final_error": -1.0}
    return f.move(agent, chain, result.angles, target, timeout, answer, tolerance=max(tolerance, MOVE_TOLERANCE))


def entries() -> list[ApiEntry]:
    """The feature's API entries (robots only)."""
    return [
        ApiEntry("_ik", "service", "Ik", t.IkRequest, t.IkResponse, ROBOT, ik,
                 "move an arm's hand to a point by IK (absolute/relative/default-pose offset) [m]"),
        ApiEntry("_ik_solve", "service", "IkSolve", t.IkSolveRequest, t.IkSolveResponse, ROBOT, ik_solve,
                 "IK for a pose in a frame; joint solution [rad], solver and simulated errors [m]", origin="ik"),
    ]
