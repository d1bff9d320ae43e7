"""The Pinocchio model against finite differences and against the physics backends."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from sigcore_ik.chain import build_chain, infer_chains, set_chain_angles, tip_pose
from sigcore_ik.model import RobotModel

from sigcore import plugins
from sigcore.world import World

WORLDS = Path(__file__).parent.parent.parent / "worlds"

SIGBOT = WORLDS / "models" / "sigbot" / "sigbot.urdf"
ARM6 = WORLDS / "models" / "arm6" / "arm6.urdf"


@pytest.mark.parametrize("urdf,base,tip", [(SIGBOT, "torso_link", "l_hand_link"), (ARM6, "base_link", "tool0")])
def test_jacobian_matches_finite_differences(urdf, base, tip) -> None:
    """The tip's world-aligned Jacobian equals central differences of its position and orientation."""
    robot = RobotModel(urdf)
    chain = build_chain(robot, "arm", base, tip)
    rng = np.random.default_rng(3)
    q0 = robot.configuration({})
    h = 1e-6
    for _ in range(10):
        x = rng.uniform(chain.lower, chain.upper)
        q = set_chain_angles(robot, chain, q0, x)
        jac = pin.computeFrameJacobian(robot.model, robot.data, q, chain.tip_frame,
                                       pin.LOCAL_WORLD_ALIGNED)[:, list(chain.idx_v)]
        r0 = tip_pose(robot, chain, q).rotation
        for k in range(chain.dof):
            dx = np.zeros(chain.dof)
            dx[k] = h
            plus = tip_pose(robot, chain, set_chain_angles(robot, chain, q0, x + dx))
            minus = tip_pose(robot, chain, set_chain_angles(robot, chain, q0, x - dx))
            linear = (plus.translation - minus.translation) / (2 * h)
            angular = pin.log3(plus.rotation @ minus.rotation.T) / (2 * h)
            np.testing.assert_allclose(jac[:3, k], linear, atol=1e-6)
            np.testing.assert_allclose(jac[3:, k], angular, atol=1e-6)
            assert np.allclose(r0 @ r0.T, np.eye(3))


def test_inferred_arms_of_sigbot() -> None:
    """Without <arm>, each gripper's chain starts where its limb branches off (the torso) and has 5 joints."""
    robot = RobotModel(SIGBOT)
    left, right = infer_chains(robot, [("l_hand_link", "left"), ("r_hand_link", "right")])
    assert (left.name, left.base, left.dof) == ("left_arm", "torso_link", 5)
    assert right.joints[0] == "r_shoulder_pan_joint" and right.joints[-1] == "r_wrist_roll_joint"


def test_chain_with_wrong_base_lists_ancestors() -> None:
    """A base that is not an ancestor of the tip is refused with the tip's ancestors."""
    robot = RobotModel(SIGBOT)
    with pytest.raises(ValueError, match="ancestors of 'l_hand_link'.*torso_link"):
        build_chain(robot, "bad", "r_shoulder_link", "l_hand_link")


def _world_fk_errors(world: World, backend_name: str, robot: str, seed: int) -> float:
    backend = plugins.get_backend(backend_name)()
    backend.build(world)
    model = RobotModel(world.resolve(next(a for a in world.agents if a.name == robot).urdf))
    rng = np.random.default_rng(seed)
    worst = 0.0
    joints = backend.joints(robot)
    for _ in range(5):
        angles = {}
        for j in joints:
            jm = model.model.joints[model.joint_id(j)]
            lo, hi = model.model.lowerPositionLimit[jm.idx_q], model.model.upperPositionLimit[jm.idx_q]
            angles[j] = rng.uniform(lo, hi) if jm.nq == 1 else rng.uniform(-np.pi, np.pi)
            backend.set_joint_angle(robot, j, angles[j])
        q = model.configuration(angles)
        pin.framesForwardKinematics(model.model, model.data, q)
        pos, quat = backend.get_pose(robot, model.root)
        base = pin.SE3(pin.Quaternion(*quat).matrix(), pos)  # Quaternion(w, x, y, z)
        for link in backend.parts(robot):
            p, qt = backend.get_pose(robot, link)
            pose = base * model.data.oMf[model.frame_id(link)]
            worst = max(worst, float(np.linalg.norm(pose.translation - p)))
            assert np.allclose(np.abs(pin.Quaternion(pose.rotation).coeffs() @ np.roll(qt, -1)), 1.0, atol=1e-6)
    return worst


@pytest.mark.parametrize("backend_name", sorted(plugins.backends()))
def test_fk_equals_backend_link_poses_sigbot(cleanup_world: World, backend_name: str) -> None:
    """Every link of robot_000 is where the backend puts it, to 1e-6 m, for random in-limit joint angles."""
    assert _world_fk_errors(cleanup_world, backend_name, "robot_000", 1) < 1e-6


@pytest.mark.parametrize("backend_name", sorted(plugins.backends()))
def test_fk_equals_backend_link_poses_arm6(arm6_world: World, backend_name: str) -> None:
    """Every link of arm_0 is where the backend puts it, to 1e-6 m, for random in-limit joint angles."""
    assert _world_fk_errors(arm6_world, backend_name, "arm_0", 2) < 1e-6


def test_arm6_urdf_is_generated() -> None:
    """worlds/models/arm6/arm6.urdf is exactly what make_arm6.py writes (nobody edited it by hand)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_arm6", ARM6.parent / "make_arm6.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.urdf() == ARM6.read_text(encoding="utf-8")
