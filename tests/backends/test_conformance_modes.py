"""Conformance: gravity, dynamics and collision modes, held humans, determinism and reset, on every backend."""

from __future__ import annotations

import numpy as np
import pytest
from conformance_worlds import robot, run

from sigcore.errors import BackendError

BOX = '<object name="o" shape="box" size="0.2 0.2 0.2" mass="1" pose="0 0 1"/>'


def _state(b, entities: list[str]) -> bytes:
    return b"".join(np.concatenate(b.get_pose(e)).tobytes() + np.concatenate(b.get_velocity(e)).tobytes()
                    for e in entities)


def test_gravity_off_floats(make_world, build) -> None:
    """With gravity off an object stays where it is (1e-9 m after 1 s); with gravity back on it falls again."""
    b = build(make_world(BOX))
    b.set_gravity_mode("o", False)
    run(b, 1.0)
    np.testing.assert_allclose(b.get_pose("o")[0], [0, 0, 1], atol=1e-9)
    b.set_gravity_mode("o", True)
    run(b, 0.2)
    assert b.get_pose("o")[0][2] < 1.0 - 0.15


def test_gravity_off_robot_floats_whole(make_world, build) -> None:
    """With gravity off a whole robot (every link) floats in the air: it moves less than 1 mm in 1 s."""
    b = build(make_world(robot(pose="0 0 2 0 0 0")))
    b.set_gravity_mode("bot", False)
    run(b, 1.0)
    np.testing.assert_allclose(b.get_pose("bot")[0], [0, 0, 2], atol=1e-3)
    np.testing.assert_allclose(b.get_pose("bot", "hand")[0], [-0.1, 0, 2.72], atol=1e-3)


def test_dynamics_off_holds(make_world, build) -> None:
    """With dynamics off an object is held exactly despite gravity and an applied force; set_pose still moves
    it; dynamics on, it falls."""
    b = build(make_world(BOX))
    b.set_dynamics_mode("o", False)
    for _ in range(200):
        b.apply_wrench("o", None, np.array([50.0, 0, 0]), np.zeros(3))
        b.step()
    np.testing.assert_allclose(b.get_pose("o")[0], [0, 0, 1], atol=1e-9)
    np.testing.assert_allclose(b.get_velocity("o")[0], 0.0, atol=1e-9)
    b.set_pose("o", np.array([1.0, 1.0, 2.0]))
    run(b, 0.5)
    np.testing.assert_allclose(b.get_pose("o")[0], [1, 1, 2], atol=1e-9)
    b.set_dynamics_mode("o", True)
    run(b, 0.2)
    assert b.get_pose("o")[0][2] < 2.0 - 0.15


def test_dynamics_off_robot_moves_by_joint_angle_only(make_world, build) -> None:
    """A held robot ignores its servos and wheel commands but takes set_joint_angle instantly and keeps it."""
    b = build(make_world(robot()))
    b.set_dynamics_mode("bot", False)
    b.set_joint_velocity("bot", "wheel_l_joint", 5.0)
    b.set_joint_target("bot", "shoulder", 1.0)
    b.set_joint_angle("bot", "elbow", 0.7)
    run(b, 0.5)
    np.testing.assert_allclose(b.get_pose("bot")[0], [0, 0, 0], atol=1e-6)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(0.0, abs=1e-9)
    assert b.get_joint_angle("bot", "elbow") == pytest.approx(0.7, abs=1e-9)


def test_static_human_held_until_dynamics_on(make_world, build) -> None:
    """A static human stands still under a push; with dynamics on the same push moves it."""
    b = build(make_world('<human name="h" pose="0 0 0"/>'))
    for _ in range(100):
        b.apply_wrench("h", None, np.array([1000.0, 0, 0]), np.zeros(3))
        b.step()
    np.testing.assert_allclose(b.get_pose("h")[0], [0, 0, 0], atol=1e-9)
    np.testing.assert_allclose(b.get_pose("h")[1], [1, 0, 0, 0], atol=1e-9)
    b.set_dynamics_mode("h", True)
    for _ in range(100):
        b.apply_wrench("h", None, np.array([1000.0, 0, 0]), np.zeros(3))
        b.step()
    assert 0.05 < b.get_com("h")[0] < 2.0  # it topples or slides (1000 N for 0.2 s on 70 kg: not flung away)


def test_human_stands_on_its_feet(make_world, build) -> None:
    """A dynamic human's frame is at its feet: it stands on the ground at z = 0 (within 3 mm) and its centre of
    mass is above it."""
    b = build(make_world('<human name="h" pose="1 2 0.01" static="false"/>'))
    run(b, 0.5)
    pos = b.get_pose("h")[0]
    np.testing.assert_allclose(pos, [1, 2, 0], atol=3e-3)
    assert 0.7 < b.get_com("h")[2] < 1.0


def test_collision_off_falls_through(make_world, build) -> None:
    """With collision off a box falls through the ground; turned back on, another box still lands on it."""
    b = build(make_world(BOX + '<object name="p" shape="box" size="0.2 0.2 0.2" pose="2 0 0.11"/>'))
    b.set_collision_mode("o", False)
    run(b, 1.0)
    assert b.get_pose("o")[0][2] < -1.0
    b.set_collision_mode("o", True)
    run(b, 1.0)
    assert b.get_pose("p")[0][2] == pytest.approx(0.1, abs=3e-3)


def test_static_object_cannot_become_dynamic(make_world, build) -> None:
    """Enabling dynamics of a static object is refused with a BackendError; disabling it is accepted."""
    b = build(make_world('<object name="w" shape="box" size="1 1 1" static="true" pose="0 0 0.5"/>'))
    b.set_dynamics_mode("w", False)
    with pytest.raises(BackendError, match="static"):
        b.set_dynamics_mode("w", True)


def test_deterministic(make_world, build) -> None:
    """Two builds of one world, in one process, stepped with the same inputs end in bitwise-identical states."""
    world = make_world(robot() + '<object name="o" shape="box" size="0.1 0.1 0.1" pose="0.6 0.3 0.05"/>'
                       '<object name="c" shape="cylinder" size="0.03 0.1" graspable="true" '
                       'pose="-0.1 0 0.8"/>')
    runs = []
    backends = [build(world), build(world)]  # both alive at once: separate engine instances
    for b in backends:
        b.attach("bot", "hand", "c")
        b.set_joint_velocity("bot", "wheel_l_joint", 3.0)
        b.set_joint_velocity("bot", "wheel_r_joint", 4.0)
        b.set_joint_target("bot", "shoulder", 0.4)
    for i in range(600):
        for b in backends:
            if i % 50 == 0:
                b.apply_wrench("o", None, np.array([2.0, 0, 0]), np.zeros(3))
            b.step()
    for b in backends:
        runs.append(_state(b, ["bot", "o", "c"]))
    assert runs[0] == runs[1]


def test_reset_restores_everything(make_world, build) -> None:
    """reset restores poses, joint angles, masses and gravity/dynamics/collision modes, and releases grasps:
    afterwards the world behaves as a fresh build (1e-9 m after 0.5 s)."""
    world = make_world(robot() + BOX + '<object name="c" shape="sphere" size="0.03" graspable="true" '
                                       'pose="-0.1 0 0.78"/>'
                       '<object name="w" shape="box" size="1 1 1" static="true" pose="3 0 0.5"/>')
    b = build(world)
    start = _state(b, ["bot", "o", "c", "w"])
    angles = [b.get_joint_angle("bot", j) for j in b.joints("bot")]
    b.attach("bot", "hand", "c")
    b.set_mass("o", 5.0)
    b.set_gravity_mode("o", False)
    b.set_collision_mode("bot", False)
    b.set_dynamics_mode("c", False)
    b.set_pose("w", np.array([4.0, 0, 0.5]))
    b.set_joint_velocity("bot", "wheel_l_joint", 4.0)
    b.set_joint_target("bot", "shoulder", 1.0)
    run(b, 0.5)
    b.reset()
    assert _state(b, ["bot", "o", "c", "w"]) == start
    assert [b.get_joint_angle("bot", j) for j in b.joints("bot")] == angles
    assert b.get_mass("o") == pytest.approx(1.0)
    fresh = build(world)
    run(b, 0.5)
    run(fresh, 0.5)
    for entity in ("bot", "o", "c"):
        np.testing.assert_allclose(b.get_pose(entity)[0], fresh.get_pose(entity)[0], atol=1e-9)
