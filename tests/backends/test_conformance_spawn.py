"""Conformance: adding and removing entities while the world runs (``Backend.add_entities`` /
``Backend.remove_entities``), on every backend.

Each test parses one world file holding every entity it will ever have, builds the backend from that world without
the entities to add (``World.with_agents``), and hands the full world to ``add_entities``, as the core does."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np
import pytest
from conformance_worlds import robot, run

from sigcore.backend import GROUND, Array, Backend
from sigcore.errors import BackendError
from sigcore.geometry import quat_to_matrix
from sigcore.world import World

MODELS = Path(__file__).resolve().parents[2] / "worlds" / "models"

URDF_EPS = 1e-6
"""Tolerance [m] of a pose given to the engine: PyBullet keeps model numbers as 32-bit floats (1e-7 relative)."""

REST = 3e-3
"""Tolerance [m] of a resting height: contact penetration and solver softness (as in the primitive-size test)."""

SIGBOT = f"""<robot name="sigbot_1" urdf="{MODELS / "sigbot" / "sigbot.urdf"}" pose="{{pose}}">
    <drive type="differential" left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.4"/>
    <gripper part="l_hand_link" grasp_radius="0.1" side="left"/>
    <gains kp="200" kv="10" max_torque="100"/>
  </robot>"""

TABLE = f'<object name="table" urdf="{MODELS / "table" / "table.urdf"}" static="true" pose="3 3 0 0 0 0"/>'
"""The clean-up world's table: top 1.2 x 0.6 m, its upper face at z = 0.70."""

BAD_URDF = """<robot name="bad">
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0"
    izz="0.01"/></inertial><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="flap"><collision><geometry><box size="0.1 0.01 0.1"/></geometry></collision></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="flap"/><origin xyz="0 0.06 0"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""
"""A URDF that parses but that no engine builds: the link on a movable joint has no ``<inertial>``."""

WorldFactory = Callable[..., World]
Builder = Callable[[World], Backend]


def _without(world: World, names: Iterable[str]) -> World:
    """``world`` without the agents ``names``."""
    gone = set(names)
    return world.with_agents(tuple(a for a in world.agents if a.name not in gone))


def _start(make_world: WorldFactory, build: Builder, body: str, later: Iterable[str]) -> tuple[Backend, World]:
    """A backend holding the world ``body`` without the entities ``later``, and the full world."""
    full = make_world(body)
    return build(_without(full, later)), full


def _snapshot(b: Backend, entities: Iterable[str]) -> list[float]:
    """Pose and velocity of every part and angle and speed of every joint of ``entities``, as exact floats."""
    values: list[float] = []
    for name in entities:
        for part in b.parts(name):
            pos, quat = b.get_pose(name, part)
            lin, ang = b.get_velocity(name, part)
            values.extend(float(x) for x in (*pos, *quat, *lin, *ang))
        for j in b.joints(name):
            values.extend((b.get_joint_angle(name, j), b.get_joint_velocity(name, j)))
    return values


def _entities_in_contact(b: Backend) -> set[frozenset[str]]:
    """Pairs of entities whose parts touch after the last step."""
    return {frozenset((b.part_of(i)[0], b.part_of(j)[0])) for i, j in b.contacts()}


def test_spawned_box_falls_and_rests(make_world, build) -> None:
    """A flat box added 0.6 m up while the world runs falls and rests on the floor at its half height (within
    3 mm; within 1 cm of where it was let go); it has the single part 'main' and no joints."""
    b, full = _start(make_world, build, '<object name="old" shape="sphere" size="0.05" pose="2 0 0.05"/>'
                                        '<object name="new" shape="box" size="0.3 0.2 0.1" pose="0 0 0.6"/>', ["new"])
    run(b, 0.2)
    b.add_entities(full, ["new"])
    assert b.parts("new") == ["main"] and b.joints("new") == []
    assert b.get_pose("new")[0] == pytest.approx([0.0, 0.0, 0.6], abs=URDF_EPS)
    run(b, 0.2)
    assert 0.3 < b.get_pose("new")[0][2] < 0.5  # falling: 0.6 - g t^2 / 2 = 0.40 m
    run(b, 1.3)
    assert b.get_pose("new")[0][2] == pytest.approx(0.05, abs=REST)
    assert b.get_pose("new")[0][:2] == pytest.approx([0.0, 0.0], abs=1e-2)
    assert float(np.linalg.norm(b.get_velocity("new")[0])) < 1e-2


def test_spawned_urdf_robot_falls_rests_lists_its_parts_and_drives(make_world, build) -> None:
    """The clean-up robot added 0.1 m above the floor while running falls and stands on its wheels (base frame
    on the floor within 1 cm: it leans on a caster; within 2 cm of where it was let go: it lands on its casters and
    rocks), lists every URDF link (root first) and movable joint, and
    its wheels at 5 rad/s (r = 0.1 m) drive it forward (more than 0.3 m in 1 s, less than 0.1 m sideways)."""
    b, full = _start(make_world, build, robot() + SIGBOT.format(pose="-2 1 0.1 0 0 0"), ["sigbot_1"])
    run(b, 0.1)
    b.add_entities(full, ["sigbot_1"])
    urdf = full.urdf("sigbot_1").model
    assert b.parts("sigbot_1")[0] == urdf.root == "base_link"
    assert sorted(b.parts("sigbot_1")) == sorted(urdf.links)
    assert b.joints("sigbot_1") == [j.name for j in urdf.movable_joints]
    assert all(b.get_joint_angle("sigbot_1", j) == pytest.approx(0.0, abs=1e-9) for j in b.joints("sigbot_1"))
    run(b, 1.5)
    pos = b.get_pose("sigbot_1")[0]
    assert pos[:2] == pytest.approx([-2.0, 1.0], abs=2e-2)
    assert pos[2] == pytest.approx(0.0, abs=1e-2)
    for wheel in ("wheel_l_joint", "wheel_r_joint"):
        b.set_joint_velocity("sigbot_1", wheel, 5.0)
    run(b, 1.0)
    moved = b.get_pose("sigbot_1")[0] - pos
    assert moved[0] > 0.3 and abs(moved[1]) < 0.1


def test_add_leaves_every_other_entity_exactly_as_it_was(make_world, build) -> None:
    """Right after an add, every part pose and velocity and every joint angle and speed of the other entities (a
    robot driving and moving its arm, a falling box, a rolling ball, a held human) is what it was before, exactly;
    and while the added entities touch none of them, and after they are removed, they move exactly as in a twin
    world that never had them."""
    body = (robot() + '<object name="box" shape="box" size="0.1 0.1 0.1" pose="2 0 1"/>'
            '<object name="ball" shape="sphere" size="0.05" pose="-2 0 0.05"/>'
            '<human name="h" pose="0 3 0" static="true"/>'
            '<object name="crate" shape="box" size="0.2 0.2 0.2" pose="4 4 0.5"/>' + SIGBOT.format(pose="-3 -3 0.2"))
    full = make_world(body)
    old = ["bot", "box", "ball", "h"]
    b, twin = (build(_without(full, ["crate", "sigbot_1"])) for _ in range(2))
    for x in (b, twin):
        x.set_joint_velocity("bot", "wheel_l_joint", 3.0)
        x.set_joint_velocity("bot", "wheel_r_joint", 2.0)
        x.set_joint_target("bot", "shoulder", 1.0)
        x.set_velocity("ball", np.array([1.0, 0.0, 0.0]))
        run(x, 0.25)
    before = _snapshot(b, old)
    b.add_entities(full, ["crate", "sigbot_1"])
    assert _snapshot(b, old) == before
    run(b, 0.5)
    run(twin, 0.5)
    assert _snapshot(b, old) == _snapshot(twin, old)
    b.remove_entities(_without(full, ["crate", "sigbot_1"]), ["crate", "sigbot_1"])
    run(b, 0.5)
    run(twin, 0.5)
    assert _snapshot(b, old) == _snapshot(twin, old)


def test_deleting_a_table_lets_what_stood_on_it_fall(make_world, build) -> None:
    """A box resting on a static table falls to the floor (half height within 3 mm) once the table is removed;
    the removed name is then refused as any unknown entity (parts, pose), and the other entities stay."""
    world = make_world(TABLE + '<object name="cup" shape="box" size="0.1 0.1 0.1" pose="3 3 0.76"/>')
    b = build(world)
    run(b, 0.5)
    assert b.get_pose("cup")[0][2] == pytest.approx(0.75, abs=REST)
    b.remove_entities(_without(world, ["table"]), ["table"])
    for call in (lambda: b.parts("table"), lambda: b.joints("table"), lambda: b.get_pose("table")):
        with pytest.raises(BackendError, match="no entity 'table'"):
            call()
    assert b.parts("cup") == ["main"]
    run(b, 1.0)
    assert b.get_pose("cup")[0] == pytest.approx([3.0, 3.0, 0.05], abs=REST)


def test_contacts_and_rays_see_added_bodies_and_forget_removed_ones(make_world, build) -> None:
    """A ray along +x hits an added box's face at 0.95 m (1 mm) and passes once it is removed; the box's contact
    with the floor is reported after a step, and after its removal no contact or part id names it."""
    b, full = _start(make_world, build, '<object name="ball" shape="sphere" size="0.05" pose="-1 0 0.05"/>'
                                        '<object name="new" shape="box" size="0.1 0.1 0.1" pose="1 0 0.05"/>',
                     ["new"])
    origin, ray = np.array([0.0, 0.0, 0.05]), np.array([[1.0, 0.0, 0.0]])
    run(b, 0.1)
    assert np.isinf(b.ray_cast(origin, ray, 5.0)[0])
    b.add_entities(full, ["new"])
    assert b.ray_cast(origin, ray, 5.0)[0] == pytest.approx(0.95, abs=1e-3)
    run(b, 0.1)
    assert frozenset(("new", GROUND)) in _entities_in_contact(b)
    assert frozenset(("ball", GROUND)) in _entities_in_contact(b)
    b.remove_entities(_without(full, ["new"]), ["new"])
    assert np.isinf(b.ray_cast(origin, ray, 5.0)[0])
    run(b, 0.01)
    assert _entities_in_contact(b) == {frozenset(("ball", GROUND))}
    ids = {i for pair in b.contacts() for i in pair}
    assert all(b.part_of(i)[0] != "new" for i in ids)


def test_several_entities_in_one_call(make_world, build) -> None:
    """One add_entities call adds a box, a sphere, a human and a robot: each is known with its parts, and the box
    and the sphere come to rest on the floor (within 3 mm)."""
    news = ["b1", "s1", "h1", "bot"]
    b, full = _start(make_world, build, '<object name="b1" shape="box" size="0.2 0.2 0.2" pose="1 0 0.5"/>'
                                        '<object name="s1" shape="sphere" size="0.1" pose="-1 0 0.5"/>'
                                        '<human name="h1" pose="0 3 0"/>' + robot("0 -2 0.05 0 0 0"), news)
    b.add_entities(full, news)
    assert [b.parts(n)[0] for n in news] == ["main", "main", "main", "base_link"]
    assert b.joints("bot") == ["wheel_l_joint", "wheel_r_joint", "shoulder", "elbow"]
    run(b, 1.0)
    assert b.get_pose("b1")[0] == pytest.approx([1.0, 0.0, 0.1], abs=REST)
    assert b.get_pose("s1")[0] == pytest.approx([-1.0, 0.0, 0.1], abs=REST)


def test_reset_after_add_and_remove(make_world, build) -> None:
    """After an add and a remove, reset puts the old entities back to their build state and the added one to its
    as-added state (its model pose, at rest; 1e-9), forgets the removed one, and the world then runs as a fresh
    build of the current world (1e-9 m after 0.5 s)."""
    body = ('<object name="a" shape="box" size="0.1 0.1 0.1" pose="0 0 0.5"/>'
            '<object name="gone" shape="sphere" size="0.05" pose="1 0 0.3"/>' + robot("0 2 0 0 0 0")
            + '<object name="new" shape="box" size="0.1 0.1 0.1" pose="-1 -1 0.6 0 0 0.5"/>')
    b, full = _start(make_world, build, body, ["new"])
    start = _snapshot(b, ["a", "bot"])
    run(b, 0.3)
    b.add_entities(full, ["new"])
    as_added = _snapshot(b, ["new"])
    b.set_joint_velocity("bot", "wheel_l_joint", 3.0)
    run(b, 0.3)
    current = _without(full, ["gone"])
    b.remove_entities(current, ["gone"])
    run(b, 0.3)
    b.reset()
    assert _snapshot(b, ["a", "bot"]) == pytest.approx(start, abs=1e-9)
    assert _snapshot(b, ["new"]) == pytest.approx(as_added, abs=1e-9)
    with pytest.raises(BackendError, match="no entity 'gone'"):
        b.parts("gone")
    fresh = build(current)
    run(b, 0.5)
    run(fresh, 0.5)
    for name in ("a", "bot", "new"):
        assert b.get_pose(name)[0] == pytest.approx(fresh.get_pose(name)[0], abs=1e-9)


def test_rejected_urdf_is_refused_naming_it_and_nothing_changes(make_world, build, tmp_path) -> None:
    """Adding a good box and a robot whose URDF the engine rejects in one call raises BackendError naming the
    robot; neither is added, and the world then runs exactly like a twin that was never asked (1e-12 m after
    0.3 s); the good box alone is added afterwards."""
    (tmp_path / "bad.urdf").write_text(BAD_URDF)
    body = ('<object name="ball" shape="sphere" size="0.05" pose="0 0 0.3"/>'
            '<object name="good" shape="box" size="0.1 0.1 0.1" pose="1 0 0.05"/>'
            '<robot name="flapper" urdf="bad.urdf" pose="2 0 0.2"/>')
    b, full = _start(make_world, build, body, ["good", "flapper"])
    twin = build(_without(full, ["good", "flapper"]))
    run(b, 0.1)
    run(twin, 0.1)
    with pytest.raises(BackendError, match="flapper"):
        b.add_entities(full, ["good", "flapper"])
    for name in ("good", "flapper"):
        with pytest.raises(BackendError, match=f"no entity '{name}'"):
            b.parts(name)
    run(b, 0.3)
    run(twin, 0.3)
    assert b.get_pose("ball")[0] == pytest.approx(twin.get_pose("ball")[0], abs=1e-12)
    b.add_entities(_without(full, ["flapper"]), ["good"])
    assert b.parts("good") == ["main"]


CAN = '<object name="{name}" shape="cylinder" size="0.03 0.1" mass="0.2" graspable="true" pose="-0.1 0 0.79"/>'
"""A graspable can just above the bot's hand (as in the grasp conformance tests)."""


def _in_hand(b: Backend, obj: str) -> Array:
    """Position [m] of ``obj`` in the bot's hand frame."""
    hand, quat = b.get_pose("bot", "hand")
    return quat_to_matrix(quat).T @ (b.get_pose(obj)[0] - hand)


def _carried(b: Backend, obj: str) -> None:
    """Assert that moving the bot's arm carries ``obj``: its position in the hand frame stays within 2 mm."""
    offset = _in_hand(b, obj)
    b.set_joint_target("bot", "shoulder", 0.6)
    run(b, 1.0)
    assert _in_hand(b, obj) == pytest.approx(offset, abs=2e-3)
    assert b.get_pose(obj)[0][2] > 0.4  # carried, not fallen


def test_added_entities_grasp_and_are_grasped(make_world, build) -> None:
    """An existing robot's gripper grasps an added graspable object and carries it; an added robot's gripper
    grasps an existing graspable object and carries it."""
    b, full = _start(make_world, build, robot(extra=' fixed="true"') + CAN.format(name="can_1"), ["can_1"])
    b.add_entities(full, ["can_1"])
    b.attach("bot", "hand", "can_1")
    _carried(b, "can_1")
    b, full = _start(make_world, build, CAN.format(name="can_2") + robot(extra=' fixed="true"'), ["bot"])
    b.set_gravity_mode("can_2", False)
    b.add_entities(full, ["bot"])
    b.attach("bot", "hand", "can_2")
    b.set_gravity_mode("can_2", True)
    _carried(b, "can_2")


def test_removing_held_or_released_objects_leaves_no_trace(make_world, build) -> None:
    """Removing an object still held (the backend releases it itself) or one grasped before leaves nothing behind:
    an object added afterwards with its collision switched off falls through the robot's base and the floor (below
    z = 0 after 0.5 s), and the robot's arm still moves."""
    body = (robot(extra=' fixed="true"') + CAN.format(name="held") + CAN.format(name="dropped")
            + '<object name="ghost" shape="box" size="0.1 0.1 0.1" pose="0.05 0 0.5"/>')
    b, full = _start(make_world, build, body, ["held", "dropped", "ghost"])
    b.add_entities(_without(full, ["held", "ghost"]), ["dropped"])
    b.attach("bot", "hand", "dropped")
    run(b, 0.1)
    b.detach("bot", "hand", "dropped")
    b.remove_entities(_without(full, ["dropped", "held", "ghost"]), ["dropped"])
    b.add_entities(_without(full, ["dropped", "ghost"]), ["held"])
    b.attach("bot", "hand", "held")
    run(b, 0.1)
    b.remove_entities(_without(full, ["dropped", "held", "ghost"]), ["held"])
    b.add_entities(_without(full, ["dropped", "held"]), ["ghost"])
    b.set_collision_mode("ghost", False)
    run(b, 0.5)
    assert b.get_pose("ghost")[0][2] < 0.0
    b.set_joint_target("bot", "shoulder", 0.6)
    run(b, 1.0)
    assert b.get_joint_angle("bot", "shoulder") == pytest.approx(0.6, abs=0.02)


def test_collision_off_after_a_released_grasp(make_world, build) -> None:
    """An object grasped, released and then set to collide with nothing passes through the robot that held it
    (falls below the floor within 0.5 s)."""
    b = build(make_world(robot(extra=' fixed="true"') + CAN.format(name="can")))
    b.attach("bot", "hand", "can")
    run(b, 0.1)
    b.detach("bot", "hand", "can")
    b.set_collision_mode("can", False)
    b.set_pose("can", np.array([0.05, 0.0, 0.5]))
    run(b, 0.5)
    assert b.get_pose("can")[0][2] < 0.0
