"""The agent handle API against the real engine state, on every registered backend (MuJoCo, PyBullet, ...): set
then get, drive then measure, grasp rules."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sigcore import plugins
from sigcore.agent import ApiError, GraspError, GraspRefusal
from sigcore.geometry import quat_from_axis_angle, quat_rotate
from sigcore.sim import Simulation
from sigcore.world import World


@pytest.fixture(params=sorted(plugins.backends()))
def sim(request: pytest.FixtureRequest, core_world: World) -> Simulation:
    """A fresh simulation of the core world on each registered backend (overrides conftest's MuJoCo-only one)."""
    return Simulation(core_world, request.param)


def test_position_round_trip(sim: Simulation) -> None:
    """set_position then position() returns the same point, also in the backend's state."""
    ball = sim.agent("ball")
    ball.set_position((1.0, -0.5, 2.0))
    np.testing.assert_allclose(ball.position(), (1.0, -0.5, 2.0), atol=1e-12)
    np.testing.assert_allclose(sim.backend.get_pose("ball")[0], (1.0, -0.5, 2.0), atol=1e-12)


def test_rotation_and_axis_angle(sim: Simulation) -> None:
    """set_rotation normalises its quaternion; set_axis_and_angle equals the same rotation."""
    cube = sim.agent("cube")
    cube.set_rotation((2.0, 0.0, 0.0, 2.0))
    q = cube.rotation()
    np.testing.assert_allclose(np.abs(q), [math.sqrt(0.5), 0, 0, math.sqrt(0.5)], atol=1e-9)
    cube.set_axis_and_angle((0, 0, 3), math.pi / 2)
    np.testing.assert_allclose(np.abs(cube.rotation()), np.abs(q), atol=1e-9)
    with pytest.raises(ApiError, match="non-zero"):
        cube.set_rotation((0, 0, 0, 0))


def test_velocities(sim: Simulation) -> None:
    """set_velocity / set_angular_velocity are read back; gravity then changes only vz."""
    ball = sim.agent("ball")
    ball.set_position((0.0, 2.0, 3.0))
    ball.set_velocity((1.0, 0.5, 0.0))
    ball.set_angular_velocity((0.0, 0.0, 2.0))
    np.testing.assert_allclose(ball.velocity(), (1.0, 0.5, 0.0), atol=1e-9)
    np.testing.assert_allclose(ball.angular_velocity(), (0.0, 0.0, 2.0), atol=1e-9)
    sim.step(50)
    v = ball.velocity()
    assert v[0] == pytest.approx(1.0, abs=1e-3)
    assert v[2] == pytest.approx(-9.81 * 50 * sim.dt, rel=0.02)


def test_add_force_gives_f_over_m(sim: Simulation) -> None:
    """A horizontal force F on a free-floating body for one step changes its velocity by F/m * dt."""
    ball = sim.agent("ball")
    ball.set_position((0.0, 2.0, 3.0))
    ball.set_gravity_mode(False)
    m = ball.mass()
    ball.add_force((6.0, 0.0, 0.0))
    sim.step(1)
    assert ball.velocity()[0] == pytest.approx(6.0 / m * sim.dt, rel=1e-3)
    sim.step(1)
    assert ball.velocity()[0] == pytest.approx(6.0 / m * sim.dt, rel=1e-3)  # force lasted one step only


def test_set_force_replaces_and_set_accel(sim: Simulation) -> None:
    """set_force replaces accumulated forces; set_accel gives the asked acceleration."""
    ball = sim.agent("ball")
    ball.set_position((0.0, 2.0, 3.0))
    ball.set_gravity_mode(False)
    ball.add_force((100.0, 0.0, 0.0))
    ball.set_force((0.0, 3.0, 0.0))
    sim.step(1)
    v = ball.velocity()
    assert v[0] == pytest.approx(0.0, abs=1e-9)
    assert v[1] == pytest.approx(3.0 / ball.mass() * sim.dt, rel=1e-3)
    ball.set_velocity((0, 0, 0))
    ball.set_accel((0.0, 0.0, 2.0))
    sim.step(1)
    assert ball.velocity()[2] == pytest.approx(2.0 * sim.dt, rel=1e-3)


def test_force_at_offset_point_spins(sim: Simulation) -> None:
    """A force at a point off the centre of mass adds a torque: the body starts to spin about the right axis."""
    heavy = sim.agent("heavy")
    heavy.set_position((0.0, -2.0, 3.0))
    heavy.set_gravity_mode(False)
    p = heavy.position()
    heavy.add_force_at_pos((0.0, 10.0, 0.0), p + np.array([0.1, 0.0, 0.0]))
    sim.step(1)
    w = heavy.angular_velocity()
    assert w[2] > 0 and abs(w[0]) < 1e-9
    heavy.set_angular_velocity((0, 0, 0))
    heavy.add_force_at_rel_pos((0.0, 10.0, 0.0), (-0.1, 0.0, 0.0))
    sim.step(1)
    assert heavy.angular_velocity()[2] < 0


def test_relative_force_follows_orientation(sim: Simulation) -> None:
    """add_rel_force pushes along the body's own x axis (world y after a 90° yaw)."""
    ball = sim.agent("ball")
    ball.set_position((0.0, 2.0, 3.0))
    ball.set_gravity_mode(False)
    ball.set_rotation(quat_from_axis_angle(np.array([0, 0, 1.0]), math.pi / 2))
    ball.add_rel_force((5.0, 0.0, 0.0))
    sim.step(1)
    v = ball.velocity()
    assert v[1] > 0 and abs(v[0]) < 1e-6 * max(1, abs(v[1]))


def test_torque_spins(sim: Simulation) -> None:
    """add_torque about z gives a positive angular velocity about z; set_torque replaces it."""
    heavy = sim.agent("heavy")
    heavy.set_position((0.0, -2.0, 3.0))
    heavy.set_gravity_mode(False)
    heavy.add_torque((0, 0, 5.0))
    sim.step(1)
    assert heavy.angular_velocity()[2] > 0
    heavy.set_angular_velocity((0, 0, 0))
    heavy.add_torque((0, 0, 5.0))
    heavy.set_torque((0, 0, -5.0))
    sim.step(1)
    assert heavy.angular_velocity()[2] < 0


def test_mass_set_get_and_validation(sim: Simulation) -> None:
    """set_mass changes the total mass; zero, negative and NaN masses are refused."""
    cube = sim.agent("cube")
    cube.set_mass(1.5)
    assert cube.mass() == pytest.approx(1.5)
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ApiError):
            cube.set_mass(bad)
    assert cube.mass() == pytest.approx(1.5)


def test_gravity_dynamics_collision_modes(sim: Simulation) -> None:
    """Gravity off floats; dynamics off holds despite gravity and forces; collision off falls through the floor."""
    ball, heavy, cube = sim.agent("ball"), sim.agent("heavy"), sim.agent("cube")
    ball.set_position((0.0, 2.0, 2.0))
    ball.set_gravity_mode(False)
    heavy.set_position((0.0, -2.0, 2.0))
    heavy.set_dynamics_mode(False)
    cube.set_collision_enable(False)
    with pytest.raises(ApiError, match="dynamics"):
        heavy.add_force((0, 0, 100.0))
    sim.step(250)
    assert ball.position()[2] == pytest.approx(2.0, abs=1e-6)
    assert heavy.position()[2] == pytest.approx(2.0, abs=1e-9)
    assert cube.position()[2] < -0.1
    assert not heavy.dynamics_mode() and not ball.gravity_mode() and not cube.collision_enable()


def test_joint_angle_target_velocity_torque(sim: Simulation) -> None:
    """set_joint_angle is instant; set_joint_target reaches the angle; set_joint_velocity turns the joint."""
    bot = sim.robot("bot")
    bot.set_joint_angle("shoulder_joint", 0.7)
    assert bot.joint_angle("shoulder_joint") == pytest.approx(0.7, abs=1e-9)
    bot.set_joint_target("elbow_joint", 0.5)
    sim.step(round(2.0 / sim.dt))
    assert bot.joint_angle("elbow_joint") == pytest.approx(0.5, abs=0.02)
    assert bot.joint_angle("shoulder_joint") == pytest.approx(0.7, abs=0.02)
    bot.set_joint_velocity("shoulder_joint", 0.5, 50.0)
    sim.step(round(0.5 / sim.dt))
    assert bot.joint_velocity("shoulder_joint") == pytest.approx(0.5, abs=0.05)
    angles = bot.all_joint_angles()
    assert set(angles) == {"wheel_l_joint", "wheel_r_joint", "shoulder_joint", "elbow_joint"}
    with pytest.raises(ApiError, match="outside the limits"):
        bot.set_joint_angle("elbow_joint", 3.0)
    with pytest.raises(ApiError, match="joints: "):
        bot.joint_angle("knee")


def test_joint_quaternion(sim: Simulation) -> None:
    """set_joint_quaternion sets the angle about the joint axis; offset adds to the current angle."""
    bot = sim.robot("bot")
    q = quat_from_axis_angle(np.array([0, 0, 1.0]), 0.4)
    bot.set_joint_quaternion("shoulder_joint", q)
    assert bot.joint_angle("shoulder_joint") == pytest.approx(0.4, abs=1e-9)
    bot.set_joint_quaternion("shoulder_joint", q, offset=True)
    assert bot.joint_angle("shoulder_joint") == pytest.approx(0.8, abs=1e-9)


def test_joint_and_part_positions(sim: Simulation) -> None:
    """Joint anchors and part frames are where the URDF puts them relative to the base."""
    bot = sim.robot("bot")
    base = bot.position()
    np.testing.assert_allclose(bot.joint_position("elbow_joint") - base, (0, 0, 0.45), atol=0.01)
    np.testing.assert_allclose(bot.part_position("hand_link") - base, (0.22, 0, 0.45), atol=0.01)
    np.testing.assert_allclose(bot.part_position("main"), base, atol=1e-12)
    with pytest.raises(ApiError, match="parts: main"):
        bot.part_position("tail")


def test_drive_straight_and_turn(sim: Simulation) -> None:
    """Wheels at ω for T s move the base ≈ ω·r·T forward (within 5 %); opposite wheels turn it in place."""
    bot = sim.robot("bot")
    sim.step(100)
    p0 = bot.position().copy()
    bot.set_wheel_velocity(3.0, 3.0)
    sim.step(round(2.0 / sim.dt))
    d = bot.position() - p0
    assert d[0] == pytest.approx(3.0 * 0.1 * 2.0, rel=0.05)  # 5 %: wheel spin-up and contact slip
    assert abs(d[1]) < 0.02
    bot.set_wheel_velocity(0.0, 0.0)
    sim.step(200)
    bot.set_base_velocity(0.0, 1.0)
    q0 = bot.rotation()
    p1 = bot.position().copy()
    sim.step(round(1.0 / sim.dt))
    yaw = math.atan2(*quat_rotate(bot.rotation(), np.array([1.0, 0, 0]))[[1, 0]]) - \
        math.atan2(*quat_rotate(q0, np.array([1.0, 0, 0]))[[1, 0]])
    assert yaw == pytest.approx(1.0, rel=0.1)  # 10 %: caster friction while turning
    assert np.linalg.norm(bot.position()[:2] - p1[:2]) < 0.05
    with pytest.raises(ApiError, match="<= 20"):
        bot.set_wheel_velocity(100.0, 0.0)


def _put_cube_at_hand(sim: Simulation, offset: float) -> None:
    cube = sim.agent("cube")
    hand = sim.robot("bot").part_position("hand_link")
    cube.set_dynamics_mode(False)
    cube.set_position(hand + np.array([offset, 0.0, 0.0]))


def test_grasp_inside_radius_follows_hand_and_release_drops(sim: Simulation) -> None:
    """A grasp within the radius succeeds; the object follows the hand; released, it falls."""
    bot = sim.robot("bot")
    _put_cube_at_hand(sim, 0.08)
    bot.grasp("hand_link", "cube")
    sim.agent("cube").set_dynamics_mode(True)
    assert sim.agent("cube").is_grasped()
    rel0 = sim.agent("cube").position() - bot.part_position("hand_link")
    bot.set_joint_target("shoulder_joint", 1.0)
    sim.step(round(1.5 / sim.dt))
    hand = bot.part_position("hand_link")
    assert np.linalg.norm(sim.agent("cube").position() - hand) == pytest.approx(np.linalg.norm(rel0), abs=0.01)
    assert bot.release("hand_link") == "cube"
    z = sim.agent("cube").position()[2]
    sim.step(round(0.3 / sim.dt))
    assert sim.agent("cube").position()[2] < z - 0.1
    assert not sim.agent("cube").is_grasped()


def test_grasp_refusals(sim: Simulation) -> None:
    """Grasps are refused with SIGVerse's reasons: beyond radius, not graspable, unknown, already grasping."""
    bot = sim.robot("bot")
    _put_cube_at_hand(sim, 0.3)
    with pytest.raises(GraspError) as e:
        bot.grasp("hand_link", "cube")
    assert e.value.reason is GraspRefusal.TOO_FAR and "grasp radius 0.15" in str(e.value)
    cases = [("hand_link", "heavy", GraspRefusal.NOT_GRASPABLE), ("hand_link", "nothing", GraspRefusal.UNKNOWN_OBJECT),
             ("base_link", "cube", GraspRefusal.NOT_A_GRIPPER), ("claw", "cube", GraspRefusal.UNKNOWN_PART)]
    for part, obj, reason in cases:
        with pytest.raises(GraspError) as e:
            bot.grasp(part, obj)
        assert e.value.reason is reason
    _put_cube_at_hand(sim, 0.05)
    bot.grasp("hand_link", "cube")
    with pytest.raises(GraspError) as e:
        bot.grasp("hand_link", "cube")
    assert e.value.reason is GraspRefusal.ALREADY_GRASPING


def test_collision_state_and_entities(sim: Simulation) -> None:
    """A resting object touches the ground; a floating one does not; entities lists every agent."""
    sim.agent("ball").set_position((0, 2, 2))
    sim.step(5)
    assert sim.agent("heavy").collision_state("main")
    assert not sim.agent("ball").collision_state()
    assert sim.agent("moderator").entities() == ["bot", "cube", "ball", "heavy", "wall", "man", "moderator"]


def test_bare_agent_has_no_body(sim: Simulation) -> None:
    """Body operations on a bare agent are refused with the list of entities."""
    with pytest.raises(ApiError, match="bare agent"):
        sim.agent("moderator").position()


def test_nan_and_wrong_lengths_refused(sim: Simulation) -> None:
    """NaN, inf and wrong vector lengths are refused and change nothing."""
    ball = sim.agent("ball")
    p = ball.position().copy()
    for bad in ((float("nan"), 0, 0), (0, float("inf"), 0), (1, 2)):
        with pytest.raises(ApiError):
            ball.set_position(bad)
    np.testing.assert_array_equal(ball.position(), p)


def test_angle_to_axis_is_an_angle(sim: Simulation) -> None:
    """angle_to_axis returns the angle (the original returned its cosine)."""
    assert sim.agent("bot").angle_to_axis("x", (1, 1, 0)) == pytest.approx(math.pi / 4)
    with pytest.raises(ApiError, match="x, y, z"):
        sim.agent("bot").angle_to_axis("w", (1, 0, 0))


def test_add_joint_torque_accelerates_the_joint(sim: Simulation) -> None:
    """A joint torque applied for one step turns the joint in its direction (against the holding servo)."""
    bot = sim.robot("bot")
    sim.step(50)
    bot.add_joint_torque("shoulder_joint", 20.0)
    sim.step(1)
    assert bot.joint_velocity("shoulder_joint") > 0.01
    with pytest.raises(ApiError, match="torque"):
        bot.add_joint_torque("shoulder_joint", float("nan"))


def test_add_force_to_part_pushes_that_part(sim: Simulation) -> None:
    """A force on one robot part (the hand) moves the robot base less than the same force on the base would turn it:
    the hand force makes the arm joint move."""
    bot = sim.robot("bot")
    sim.step(50)
    a0 = bot.joint_angle("shoulder_joint")
    bot.add_force_to_part("forearm_link", (0.0, 200.0, 0.0))
    sim.step(5)
    assert bot.joint_angle("shoulder_joint") > a0 + 1e-4
    with pytest.raises(ApiError, match="parts: main"):
        bot.add_force_to_part("tail", (0, 1, 0))


def test_set_owner_recorded_and_validated(sim: Simulation) -> None:
    """_setOwner records the owner of a part; an unknown owner is refused; a reset forgets owners."""
    from sigcore.api import api_table, call

    entry = next(e for e in api_table() if e.suffix == "_setOwner")
    assert call(sim, entry, "moderator", {"name": "cube", "part": "main", "owner": "bot"})["success"]
    assert sim.entities.owners.get("cube", "main") == sim.agent("cube").owner() == "bot"
    r = call(sim, entry, "moderator", {"name": "cube", "part": "main", "owner": "nobody"})
    assert not r["success"] and "no agent 'nobody'" in r["message"]
    sim.reset()
    assert sim.agent("cube").owner() is None
