"""Conformance: a person's body (REP-155 links and joints, capsules), held kinematically, seen by rays, touching
others by link, on every backend."""

from __future__ import annotations

import numpy as np
import pytest
from conformance_worlds import robot, run

from sigcore.errors import BackendRefusal

REP155_LINKS = {"body", "waist", "torso", "head", "l_shoulder", "l_elbow", "l_wrist", "l_hip", "l_knee", "l_ankle",
                "r_shoulder", "r_elbow", "r_wrist", "r_hip", "r_knee", "r_ankle"}
REP155_JOINTS = {"waist", "r_head", "y_head", "p_head", "l_y_shoulder", "l_p_shoulder", "l_r_shoulder", "l_elbow",
                 "r_y_shoulder", "r_p_shoulder", "r_r_shoulder", "r_elbow", "l_y_hip", "l_p_hip", "l_r_hip", "l_knee",
                 "r_y_hip", "r_p_hip", "r_r_hip", "r_knee"}


def test_a_person_has_the_rep155_links_and_joints(make_world, build) -> None:
    """A person's parts are its feet frame ``main`` then REP-155's links; its joints are REP-155's (plus the two
    ankles); its feet stand on the floor and its head reaches its height."""
    world = make_world('<human name="h" pose="1 2 0" height="1.8"/>')
    b = build(world)
    assert b.parts("h")[0] == "main" and REP155_LINKS <= set(b.parts("h"))
    assert REP155_JOINTS <= set(b.joints("h")) and set(b.joints("h")) - REP155_JOINTS == {"l_ankle", "r_ankle"}
    np.testing.assert_allclose(b.get_pose("h")[0], [1, 2, 0], atol=1e-9)
    assert b.get_pose("h", "head")[0][2] == pytest.approx(1.8 - 0.5 * 1.8 / 7.5, abs=1e-6)
    assert b.get_mass("h") == pytest.approx(70.0, rel=1e-6)
    run(b, 0.2)
    np.testing.assert_allclose(b.get_pose("h")[0], [1, 2, 0], atol=1e-9)  # held where it stands


def test_set_joint_angle_puts_each_link_at_its_forward_kinematics(make_world, build) -> None:
    """After ``set_joint_angle`` on a turned person, the wrist and ankle are where the URDF's joints put them
    (within 1 mm), and stay there while stepping."""
    world = make_world('<human name="h" pose="1 -1 0 0 0 0.7"/>')
    b = build(world)
    angles = {"l_y_shoulder": 0.3, "l_p_shoulder": 1.1, "l_r_shoulder": -0.4, "l_elbow": 0.9, "waist": 0.2,
              "r_r_hip": 0.5, "r_knee": -0.8, "r_ankle": 0.3}
    for joint, angle in angles.items():
        b.set_joint_angle("h", joint, angle)
    run(b, 0.1)
    feet = b.get_pose("h")
    for link in ("l_wrist", "r_ankle", "head"):
        want_p, want_q = world.urdf("h").model.link_pose(link, angles, *feet)
        got_p, got_q = b.get_pose("h", link)
        np.testing.assert_allclose(got_p, want_p, atol=1e-3)
        assert abs(float(np.dot(got_q, want_q))) == pytest.approx(1.0, abs=1e-6)
    assert b.get_joint_angle("h", "l_elbow") == pytest.approx(0.9, abs=1e-9)


def _clusters(b, origin: np.ndarray, yaw_span: float = 0.5, n: int = 1001) -> list[np.ndarray]:
    """The hit points of a planar fan of rays from ``origin`` along +x, grouped into runs of neighbouring rays."""
    yaws = np.linspace(-yaw_span, yaw_span, n)
    dirs = np.stack([np.cos(yaws), np.sin(yaws), np.zeros(n)], axis=1)
    dist = b.ray_cast(origin, dirs, 5.0, exclude="bot")
    groups: list[list[int]] = []
    for i in np.flatnonzero(np.isfinite(dist)):
        if groups and i == groups[-1][-1] + 1:
            groups[-1].append(int(i))
        else:
            groups.append([int(i)])
    return [origin + dirs[g] * dist[g][:, None] for g in groups]


def test_a_lidar_sees_a_persons_two_legs_and_their_stride(make_world, build) -> None:
    """A planar lidar 0.25 m high sees a person standing 2 m away (facing it) as two legs, each 0.08-0.2 m wide;
    when the person takes a stride, the legs move apart."""
    b = build(make_world(robot() + '<human name="h" pose="2.1 0 0 0 0 3.14159"/>'))
    origin = b.get_pose("bot", "lidar_link")[0]
    assert 0.2 <= origin[2] <= 0.3
    legs = _clusters(b, origin)
    assert len(legs) == 2
    widths = [float(np.linalg.norm(leg[-1] - leg[0])) for leg in legs]
    assert all(0.08 <= w <= 0.2 for w in widths), widths
    apart = float(np.linalg.norm(legs[0].mean(axis=0) - legs[1].mean(axis=0)))
    b.set_joint_angle("h", "l_r_hip", 0.45)
    b.set_joint_angle("h", "r_r_hip", -0.3)
    b.set_joint_angle("h", "r_knee", -0.3)
    legs = _clusters(b, origin)
    assert len(legs) == 2
    stride = float(np.linalg.norm(legs[0].mean(axis=0) - legs[1].mean(axis=0)))
    assert stride > apart + 0.1, (apart, stride)


def test_a_static_person_is_not_pushed_over_and_pushes_a_box(make_world, build) -> None:
    """A 1000 N push does not move a (static) person; moved by set_pose in 2 mm steps into a 0.5 kg box in front
    of one leg, the person shoves the box along."""
    b = build(make_world('<human name="h" pose="0 0 0"/>'
                         '<object name="box" shape="box" size="0.2 0.2 0.2" mass="0.5" pose="0.35 0.14 0.1"/>'))
    for _ in range(100):
        b.apply_wrench("h", "torso", np.array([1000.0, 0, 0]), np.zeros(3))
        b.step()
    np.testing.assert_allclose(b.get_pose("h")[0], [0, 0, 0], atol=1e-9)
    for i in range(250):
        b.set_pose("h", np.array([0.002 * (i + 1), 0.0, 0.0]))
        b.step()
    assert b.get_pose("h")[0][0] == pytest.approx(0.5, abs=1e-9)
    assert b.get_pose("box")[0][0] > 0.55


def test_a_robot_driving_into_a_person_touches_its_legs(make_world, build) -> None:
    """A robot driven into a person touches it by link (a shank or a foot), and does not move it."""
    b = build(make_world(robot() + '<human name="h" pose="0.55 0 0 0 0 3.14159"/>'))
    for _ in range(600):
        b.set_joint_velocity("bot", "wheel_l_joint", 4.0)
        b.set_joint_velocity("bot", "wheel_r_joint", 4.0)
        b.step()
    touched = {b.part_of(x) for pair in b.contacts() for x in pair} | set()
    links = {part for entity, part in touched if entity == "h"}
    pairs = {(b.part_of(x)[0], b.part_of(y)[0]) for x, y in b.contacts()}
    assert ("bot", "h") in pairs or ("h", "bot") in pairs
    assert links & {"l_knee", "r_knee", "l_ankle", "r_ankle", "l_hip", "r_hip"}
    np.testing.assert_allclose(b.get_pose("h")[0], [0.55, 0, 0], atol=1e-9)


def test_motor_commands_to_a_persons_joints_are_refused(make_world, build) -> None:
    """A person's joints have no motor: targets, velocities and torques are refused with the way that works; an
    unknown joint lists the person's joints."""
    b = build(make_world('<human name="h"/>'))
    for command in (lambda: b.set_joint_target("h", "l_knee", -0.5),
                    lambda: b.set_joint_velocity("h", "l_knee", 1.0),
                    lambda: b.add_joint_torque("h", "l_knee", 1.0)):
        with pytest.raises(BackendRefusal, match="no motor.*set_joint_angle"):
            command()
    with pytest.raises(BackendRefusal, match="l_knee"):
        b.get_joint_angle("h", "knee")


def test_a_dynamic_person_is_a_mannequin(make_world, build) -> None:
    """With ``static="false"`` the person's root is free (it stands on its feet, falls when pushed hard) while its
    joints keep the angles they were given."""
    b = build(make_world('<human name="h" pose="0 0 0.01" static="false"/>'))
    b.set_joint_angle("h", "l_elbow", 1.2)
    run(b, 0.5)
    assert b.get_pose("h")[0][2] == pytest.approx(0.0, abs=0.01)  # the feet sink a little: soft contacts
    assert b.get_joint_angle("h", "l_elbow") == pytest.approx(1.2, abs=0.01)  # a stiff lock, not a rigid one
    for _ in range(200):
        b.apply_wrench("h", "torso", np.array([300.0, 0, 0]), np.zeros(3))
        b.step()
    assert 0.05 < b.get_com("h")[0] < 2.0  # pushed over, not flung away
    assert b.get_joint_angle("h", "l_elbow") == pytest.approx(1.2, abs=0.05)
