"""Conformance: contacts, falling bodies, collision events and lidar rays, on every backend."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conformance_worlds import G, robot, run

from sigcore.agent.events import CollisionEvent

# A closed room. Inner faces of the walls: x = -2 .. 2.5, y = -1.5 .. 1.5; walls 1 m high.
ROOM = (
    '<object name="wall_e" shape="box" size="0.2 3.4 1" static="true" pose="2.6 0 0.5"/>'
    '<object name="wall_w" shape="box" size="0.2 3.4 1" static="true" pose="-2.1 0 0.5"/>'
    '<object name="wall_n" shape="box" size="4.9 0.2 1" static="true" pose="0.25 1.6 0.5"/>'
    '<object name="wall_s" shape="box" size="4.9 0.2 1" static="true" pose="0.25 -1.6 0.5"/>'
)
X_MIN, X_MAX, Y_MIN, Y_MAX = -2.0, 2.5, -1.5, 1.5


def _named(b) -> set[tuple[tuple[str, str], tuple[str, str]]]:
    return {(b.part_of(x), b.part_of(y)) for x, y in b.contacts()}


def _room_distance(origin: np.ndarray, d: np.ndarray) -> float:
    ts = []
    for lo, hi, o, v in ((X_MIN, X_MAX, origin[0], d[0]), (Y_MIN, Y_MAX, origin[1], d[1])):
        if v > 1e-12:
            ts.append((hi - o) / v)
        elif v < -1e-12:
            ts.append((lo - o) / v)
    return min(ts)


# ------------------------------------------------------------------------------------------------- contacts
def test_box_on_ground(make_world, build) -> None:
    """A box resting on the ground gives exactly the pair (ground, box/main), as (low id, high id)."""
    b = build(make_world('<object name="box" shape="box" size="0.2 0.2 0.2" pose="0 0 0.1"/>'))
    run(b, 0.2)
    assert all(low < high for low, high in b.contacts())
    assert _named(b) == {(("ground", "main"), ("box", "main"))}


def test_robot_links_touching_ground(make_world, build) -> None:
    """A robot standing on the ground touches it with its wheels and casters, by URDF link name."""
    b = build(make_world(robot()))
    run(b, 0.2)
    assert _named(b) == {(("ground", "main"), ("bot", link)) for link in ("wheel_l", "wheel_r", "caster_f",
                                                                         "caster_b")}


def test_stacked_objects_and_no_self_pairs(make_world, build) -> None:
    """A box on a box gives an object-object pair; no pair is ever within one entity."""
    b = build(make_world('<object name="a" shape="box" size="0.3 0.3 0.2" pose="0 0 0.1"/>'
                         '<object name="c" shape="box" size="0.1 0.1 0.1" pose="0 0 0.25"/>'
                         + robot("2 0 0 0 0 0")))
    run(b, 0.3)
    named = _named(b)
    assert (("a", "main"), ("c", "main")) in named
    assert all(x[0] != y[0] for x, y in named)


def test_no_contacts_in_the_air(make_world, build) -> None:
    """Nothing touching gives the empty set, and part id 0 is the ground."""
    b = build(make_world('<object name="box" shape="box" size="0.2 0.2 0.2" pose="0 0 3"/>'))
    b.step()
    assert b.contacts() == frozenset()
    assert b.part_of(0) == ("ground", "main")


def test_drop_time(make_world, build) -> None:
    """A box dropped from 1 m (bottom face) first touches the ground at t = sqrt(2h/g) within 2 steps (4 ms):
    a contact is reported once the body touches, not while it is still in the air."""
    b = build(make_world('<object name="box" shape="box" size="0.1 0.1 0.1" pose="0 0 1.05"/>'))
    expected = math.sqrt(2 * 1.0 / G)
    steps = 0
    while not b.contacts():
        b.step()
        steps += 1
        assert steps < 1000
    assert steps * 0.002 == pytest.approx(expected, abs=0.004)


def test_collision_events_through_simulation(make_world, simulate) -> None:
    """Simulation reports a CollisionEvent when a falling box lands on another object (both sides), once, and
    none while they are apart."""
    sim = simulate(make_world('<object name="base" shape="box" size="0.4 0.4 0.2" static="true" pose="0 0 0.1"/>'
                              '<object name="box" shape="box" size="0.1 0.1 0.1" pose="0 0 0.5"/>'))
    events: list[CollisionEvent] = []
    sim.events.subscribe("collision", events.append)
    sim.step(50)
    assert not [e for e in events if "box" in (e.agent, e.other)]  # 0.1 s: still falling (lands at 0.22 s)
    sim.step(250)
    pairs = {(e.agent, e.other) for e in events}
    assert ("box", "base") in pairs and ("base", "box") in pairs
    assert sum(1 for e in events if (e.agent, e.other) == ("box", "base")) == 1  # resting: no repeats


# ----------------------------------------------------------------------------------------------------- rays
def test_room_distances_exclude_own_robot(make_world, build) -> None:
    """From the lidar link, every ray of a 360-beam fan hits a wall at the analytic distance, within 1 cm,
    through the own robot's arm."""
    b = build(make_world(ROOM + robot(pose=f"0.3 -0.2 0 0 0 {math.radians(30)}")))
    origin = b.get_pose("bot", "lidar_link")[0]
    angles = np.linspace(-math.pi, math.pi, 360, endpoint=False) + 0.0123
    dirs = np.stack([np.cos(angles), np.sin(angles), np.zeros(360)], axis=1)
    dist = b.ray_cast(origin, dirs, 10.0, exclude="bot")
    expected = np.array([_room_distance(origin, d) for d in dirs])
    np.testing.assert_allclose(dist, expected, atol=0.01)


def test_lidar_scan_in_room(make_world, simulate) -> None:
    """The robot's lidar, scanned by the Simulation at its rate, returns the analytic room ranges within 1 cm."""
    sim = simulate(make_world(ROOM + robot(pose="0.3 -0.2 0 0 0 0.5")))
    sim.step(50)  # one scan period at 10 Hz
    lidar = sim.entities.lidars[0]
    assert lidar.last is not None
    pos, quat = sim.backend.get_pose("bot", "lidar_link")
    angles = lidar.angle_min + lidar.increment * np.arange(len(lidar.last.ranges))
    yaw = 2 * math.atan2(quat[3], quat[0])
    dirs = np.stack([np.cos(angles + yaw), np.sin(angles + yaw), np.zeros_like(angles)], axis=1)
    expected = np.array([_room_distance(pos, d) for d in dirs])
    np.testing.assert_allclose(lidar.last.ranges, expected, atol=0.01)


def test_own_robot_hit_without_exclude(make_world, build) -> None:
    """Without exclude, the ray backwards from the lidar hits the robot's own arm 0.17 m away (0.2 - radius),
    within 1e-6 m; with it, the wall behind."""
    b = build(make_world(ROOM + robot()))
    origin = b.get_pose("bot", "lidar_link")[0]
    back = np.array([[-1.0, 0.0, 0.0]])
    assert b.ray_cast(origin, back, 10.0)[0] == pytest.approx(0.2 - 0.03, abs=1e-6)
    assert b.ray_cast(origin, back, 10.0, exclude="bot")[0] == pytest.approx(0.1 - X_MIN, abs=1e-6)


def test_max_range_gives_inf(make_world, build) -> None:
    """Rays with nothing within max_range return inf; the others their distance."""
    b = build(make_world(ROOM + robot()))
    origin = b.get_pose("bot", "lidar_link")[0]
    dirs = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    dist = b.ray_cast(origin, dirs, 2.0, exclude="bot")
    assert dist[0] == np.inf  # east wall 2.4 m away
    assert dist[1] == pytest.approx(1.5, abs=1e-6)
    assert dist[2] == np.inf  # up: open sky


def test_other_entities_are_hit(make_world, build) -> None:
    """Objects, humans and other robots are hit by rays that exclude the sensor's robot."""
    hip = 0.6 * 1.7 / 7.5  # the left leg of a person 1.7 m tall at its y = 0.136 m (sigcore.world.body)
    b = build(make_world(ROOM + robot() + f'<human name="h" pose="1.5 {-hip} 0"/>'
                         '<object name="o" shape="box" size="0.2 0.2 0.2" pose="0 1 0.25"/>'))
    origin = b.get_pose("bot", "lidar_link")[0]
    slanted = np.array([-0.1, 1.0, 0.0])
    dirs = np.array([[1.0, 0.0, 0.0], slanted / np.linalg.norm(slanted)])
    dist = b.ray_cast(origin, dirs, 10.0, exclude="bot")
    r_shank = 0.06
    assert dist[0] == pytest.approx(1.5 - r_shank - 0.1, abs=1e-6)
    assert 0.85 < dist[1] < 0.95


def test_transparent_and_collision_off_objects_are_hit(make_world, build) -> None:
    """Rays see collision geometry: a fully transparent object, and one with collision off, are hit."""
    b = build(make_world('<object name="glass" shape="box" size="0.2 0.2 0.2" static="true" color="1 1 1 0" '
                         'pose="1 0 0.1"/>'))
    ray = np.array([[1.0, 0.0, 0.0]])
    assert b.ray_cast(np.array([0.0, 0.0, 0.1]), ray, 10.0)[0] == pytest.approx(0.9, abs=1e-6)
    b.set_collision_mode("glass", False)
    assert b.ray_cast(np.array([0.0, 0.0, 0.1]), ray, 10.0)[0] == pytest.approx(0.9, abs=1e-6)


def test_rays_see_moved_state(make_world, build) -> None:
    """A ray cast right after set_pose sees the object where it was put."""
    b = build(make_world(ROOM + '<object name="o" shape="box" size="0.2 0.2 0.2" pose="0 1 0.25"/>'))
    b.set_pose("o", np.array([1.0, 0.0, 0.25]))
    dist = b.ray_cast(np.array([0.0, 0.0, 0.25]), np.array([[1.0, 0.0, 0.0]]), 10.0)
    assert dist[0] == pytest.approx(0.9, abs=1e-6)


def test_ray_hits_see_only_the_entities_among_and_name_them(make_world, build) -> None:
    """``ray_hits`` passes through what is not among the entities asked about (the robot, a person, a box) and
    names the one it hits: east through the robot, a box and a person's legs to the east wall (within 1e-6 m); with
    the box asked about too, the box; among nothing, no hit."""
    hip = 0.6 * 1.7 / 7.5
    b = build(make_world(ROOM + robot() + f'<human name="h" pose="1.5 {-hip} 0"/>'
                         '<object name="o" shape="box" size="0.2 0.2 0.2" pose="0.8 0 0.1"/>'))
    walls = ["wall_e", "wall_w", "wall_n", "wall_s"]
    origin = np.array([0.0, 0.0, 0.1])
    dirs = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    dist, names = b.ray_hits(origin, dirs, 10.0, walls)
    assert names == ["wall_e", "wall_n", None]
    np.testing.assert_allclose(dist[:2], [X_MAX, Y_MAX], atol=1e-6)
    assert dist[2] == np.inf
    dist, names = b.ray_hits(origin, dirs[:1], 10.0, [*walls, "o"])
    assert names == ["o"] and dist[0] == pytest.approx(0.7, abs=1e-6)
    dist, names = b.ray_hits(origin, dirs[:1], 10.0, [])
    assert names == [None] and dist[0] == np.inf
