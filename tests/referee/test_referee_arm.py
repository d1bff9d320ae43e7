"""sigbot's closed-form arm IK (hand pointing down) against the backend's link poses."""

from __future__ import annotations

import numpy as np
import pytest
from referee_worlds import ROOT
from sigcore_referee.arm import TUCK, hand_down, joint_names

from sigcore.agent.exceptions import UnreachableError
from sigcore.geometry import quat_rotate
from sigcore.sim import Simulation
from sigcore.world import parse_world


@pytest.fixture(scope="module")
def sim() -> Simulation:
    """The clean-up world (robot_000 at (-4, 0), yaw 0)."""
    return Simulation(parse_world(ROOT / "worlds" / "cleanup.xml"), "mujoco")


@pytest.mark.parametrize(("side", "target"), [
    ("l", (0.50, 0.20, 0.79)), ("r", (0.50, -0.20, 0.83)), ("l", (0.52, 0.10, 0.65)), ("r", (0.52, -0.10, 0.65)),
    ("l", (0.45, 0.35, 0.85)), ("r", (0.55, 0.0, 0.75)),
])
def test_hand_reaches_the_point_pointing_down(sim: Simulation, side: str, target: tuple[float, float, float]
                                              ) -> None:
    """Setting the IK pose puts the grasp point within 1 mm of the target, hand z axis up (pointing down)."""
    robot = sim.robot("robot_000")
    for name, angle in zip(joint_names(side), hand_down(side, *target), strict=True):
        robot.set_joint_angle(name, angle)
    base, q = sim.backend.get_pose("robot_000")
    hand, hq = sim.backend.get_pose("robot_000", f"{side}_hand_link")
    local = quat_rotate(np.array([q[0], -q[1], -q[2], -q[3]]), hand - base)
    assert np.allclose(local, target, atol=1e-3)
    assert quat_rotate(hq, np.array([0.0, 0.0, 1.0]))[2] > 0.999


def test_readme_pose_is_reproduced() -> None:
    """The sigbot README's table-top pose: hand 0.50 ahead, 0.20 left, z 0.79 -> [0, 0.59, 1.30, -1.89, 0]."""
    assert hand_down("l", 0.50, 0.20, 0.79) == pytest.approx((0.0, 0.59, 1.30, -1.89, 0.0), abs=0.005)
    assert len(TUCK) == 5


@pytest.mark.parametrize(("target", "why"), [((1.2, 0.2, 0.8), "reachable"), ((0.5, 0.2, 0.95), "beyond")])
def test_unreachable_points_are_refused(target: tuple[float, float, float], why: str) -> None:
    """Too far, or a joint beyond its limit, raises UnreachableError saying which."""
    with pytest.raises(UnreachableError, match=why):
        hand_down("l", *target)
