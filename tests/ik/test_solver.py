"""The damped least-squares solver: reachable targets, limits, unreachable targets."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from sigcore_ik.chain import Chain, build_chain, set_chain_angles, tip_pose
from sigcore_ik.model import RobotModel
from sigcore_ik.solver import ROTATION_PER_METRE, solve

MODELS = Path(__file__).parent.parent.parent / "worlds" / "models"
CHAINS = [("sigbot/sigbot.urdf", "torso_link", "l_hand_link"), ("sigbot/sigbot.urdf", "torso_link", "r_hand_link"),
          ("arm6/arm6.urdf", "base_link", "tool0")]


def _setup(urdf: str, base: str, tip: str) -> tuple[RobotModel, Chain]:
    robot = RobotModel(MODELS / urdf)
    return robot, build_chain(robot, "arm", base, tip)


@pytest.mark.parametrize("position_only", [True, False])
@pytest.mark.parametrize("urdf,base,tip", CHAINS)
def test_reaches_random_reachable_targets(urdf: str, base: str, tip: str, position_only: bool) -> None:
    """Targets from random in-limit configurations are reached to 0.1 mm (and 1e-3 rad) from another start,
    within the joint limits."""
    robot, chain = _setup(urdf, base, tip)
    rng = np.random.default_rng(7)
    q0 = robot.configuration({})
    for _ in range(40):
        target = tip_pose(robot, chain, set_chain_angles(robot, chain, q0, rng.uniform(chain.lower, chain.upper)))
        start = set_chain_angles(robot, chain, q0, rng.uniform(chain.lower, chain.upper))
        result = solve(robot, chain, start, target, position_only, 1e-4)
        assert result.success
        assert np.all(result.angles >= chain.lower) and np.all(result.angles <= chain.upper)
        reached = tip_pose(robot, chain, set_chain_angles(robot, chain, q0, result.angles))
        assert np.linalg.norm(reached.translation - target.translation) <= 1e-4
        if not position_only:
            assert np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation)) <= ROTATION_PER_METRE * 1e-4


def test_warm_start_at_the_solution_takes_one_iteration() -> None:
    """Started at a configuration that already reaches the target, the solver returns it unchanged."""
    robot, chain = _setup(*CHAINS[2])
    x = np.array([0.3, -1.0, 1.2, -0.5, 0.7, 0.2])
    q = set_chain_angles(robot, chain, robot.configuration({}), x)
    result = solve(robot, chain, q, tip_pose(robot, chain, q), False, 1e-4)
    assert result.success and result.iterations == 1
    np.testing.assert_allclose(result.angles, x)


def test_unreachable_target_reports_residual() -> None:
    """A point 2 m from the shoulder fails, with the residual distance of the closest configuration found."""
    robot, chain = _setup(*CHAINS[2])
    q0 = robot.configuration({})
    target = pin.SE3(np.eye(3), np.array([2.0, 0.0, 0.1]))
    result = solve(robot, chain, q0, target, True, 1e-4)
    assert not result.success
    reach = 0.425 + 0.39225 + 0.09465 + 0.0823 + 0.2
    assert 2.0 - reach < result.position_error < 2.0
    assert np.all(result.angles >= chain.lower) and np.all(result.angles <= chain.upper)


def test_target_outside_joint_limits_fails() -> None:
    """sigbot's hand cannot reach behind its back (shoulder pitch >= -0.8 rad): the solver says so."""
    robot, chain = _setup(*CHAINS[0])
    q0 = robot.configuration({})
    target = pin.SE3(np.eye(3), np.array([-0.75, 0.2, 0.9]))
    result = solve(robot, chain, q0, target, True, 1e-4)
    assert not result.success and result.position_error > 0.05
