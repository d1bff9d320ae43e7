"""The clean-up world's assets: worlds/cleanup.xml and the URDF models under worlds/models/."""

from __future__ import annotations

import importlib.util
import math
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from lxml import etree

from sigcore.world import Human, Object, Robot, World, parse_world, read_urdf
from sigcore.world.urdf import UrdfModel

WORLDS = Path(__file__).resolve().parent.parent / "worlds"
MODELS = WORLDS / "models"
SIGBOT = MODELS / "sigbot" / "sigbot.urdf"
TRASHBOX = MODELS / "trashbox" / "trashbox.urdf"
URDFS = sorted(MODELS.glob("*/*.urdf"))
TRASH = ("can_0", "petbottle_1", "apple_2")
BOXES = ("trashbox_0", "trashbox_1", "trashbox_2")
TABLE_TOP = 0.70


# ---------------------------------------------------------------------------------------------- helpers
@pytest.fixture(scope="module")
def world() -> World:
    """The clean-up world."""
    return parse_world(WORLDS / "cleanup.xml")


def _obj(world: World, name: str) -> Object:
    agent = world.agent(name)
    assert isinstance(agent, Object)
    return agent


def _floats(text: str | None, default: str = "0 0 0") -> np.ndarray:
    return np.array([float(v) for v in (text or default).split()])


def _rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    r, p, y = rpy
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    return rz @ ry @ rx


def _half_extents(geometry: etree._Element) -> np.ndarray:
    shape = geometry[0]
    if shape.tag == "box":
        return _floats(shape.get("size")) / 2
    if shape.tag == "cylinder":
        r, h = float(shape.get("radius", "0")), float(shape.get("length", "0"))
        return np.array([r, r, h / 2])
    if shape.tag == "sphere":
        return np.full(3, float(shape.get("radius", "0")))
    raise AssertionError(f"unexpected geometry <{shape.tag}>")


def _collision_boxes(path: Path) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """(centre, half extents) of each collision element's axis-aligned box, in the (single) link's frame."""
    for collision in etree.parse(str(path)).getroot().iter("collision"):
        origin = collision.find("origin")
        xyz = _floats(origin.get("xyz") if origin is not None else None)
        rot = _rpy_matrix(_floats(origin.get("rpy") if origin is not None else None))
        geometry = collision.find("geometry")
        assert geometry is not None
        yield xyz, np.abs(rot) @ _half_extents(geometry)


def _footprint(world: World, name: str) -> tuple[np.ndarray, np.ndarray]:
    """World x-y box (min, max) of an object, furniture or wall (poses in the world have yaw 0 only)."""
    obj = _obj(world, name)
    assert obj.pose.rpy == (0.0, 0.0, 0.0), "footprints assume unrotated objects"
    centre = np.array(obj.pose.xyz[:2])
    if obj.urdf is not None:
        boxes = list(_collision_boxes(world.resolve(obj.urdf)))
        lo = np.min([c[:2] - h[:2] for c, h in boxes], axis=0)
        hi = np.max([c[:2] + h[:2] for c, h in boxes], axis=0)
        return centre + lo, centre + hi
    assert obj.size is not None
    half = {"box": np.array(obj.size[:2]) / 2, "cylinder": np.full(2, obj.size[0]),
            "sphere": np.full(2, obj.size[0])}[str(obj.shape)]
    return centre - half, centre + half


def _gap(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> float:
    """Distance [m] between two x-y boxes (0 if they overlap)."""
    d = np.maximum(0.0, np.maximum(a[0] - b[1], b[0] - a[1]))
    return float(np.hypot(*d))


def _chain(urdf: UrdfModel, base: str, tip: str) -> list[str]:
    """Joint names from link ``base`` down to link ``tip``."""
    by_child = {j.child: j for j in urdf.joints}
    names, link = [], tip
    while link != base:
        joint = by_child[link]
        names.append(joint.name)
        link = joint.parent
    return names[::-1]


def _trashbox_opening() -> tuple[float, float]:
    """Inner opening (x, y) [m] of the trash box: between the inner faces of its walls."""
    boxes = [(c, h) for c, h in _collision_boxes(TRASHBOX) if c[2] - h[2] > 0]  # the walls (on the floor)
    inner_x = min(abs(c[0]) - h[0] for c, h in boxes if h[1] > h[0])
    inner_y = min(abs(c[1]) - h[1] for c, h in boxes if h[0] > h[1])
    return 2 * inner_x, 2 * inner_y


# ---------------------------------------------------------------------------------------------- the world
def test_cleanup_parses_with_expected_agents(world: World) -> None:
    """cleanup.xml parses and has the robot, moderator, a human, three trash items and three trash boxes."""
    kinds = {a.name: a.kind for a in world.agents}
    assert kinds["robot_000"] == "robot"
    assert kinds["moderator_0"] == "agent"
    assert kinds["man_0"] == "human"
    assert all(kinds[n] == "object" for n in (*TRASH, *BOXES, "table_0", "table_1", "wagon"))
    assert {a.name for a in world.agents if isinstance(a, Object) and "wall" in a.tags} == {
        "wall_north", "wall_south", "wall_east", "wall_west"}


def test_cleanup_tags(world: World) -> None:
    """Trash, trash boxes, furniture and walls carry the tags the referee relies on."""
    assert _obj(world, "can_0").tags == ("trash", "can")
    assert _obj(world, "petbottle_1").tags == ("trash", "petbottle")
    assert _obj(world, "apple_2").tags == ("trash", "burnable")
    assert _obj(world, "trashbox_0").tags == ("trashbox", "recyclable", "petbottle")
    assert _obj(world, "trashbox_1").tags == ("trashbox", "burnable")
    assert _obj(world, "trashbox_2").tags == ("trashbox", "can")
    for name in ("table_0", "table_1", "wagon"):
        assert "furniture" in _obj(world, name).tags


def test_each_trash_item_has_exactly_one_matching_box(world: World) -> None:
    """Every trash item shares a category tag with exactly one trash box."""
    for item in TRASH:
        category = set(_obj(world, item).tags) - {"trash"}
        matching = [box for box in BOXES if category & (set(_obj(world, box).tags) - {"trashbox"})]
        assert len(matching) == 1, (item, matching)


def test_trash_is_graspable_dynamic_and_on_a_table_near_its_edge(world: World) -> None:
    """Each trash item is graspable, not static, rests on a table top and lies within 0.25 m of its edge."""
    for item in TRASH:
        obj = _obj(world, item)
        assert obj.graspable and not obj.static
        assert obj.size is not None
        half_height = obj.size[1] / 2 if obj.shape == "cylinder" else obj.size[0]
        assert obj.pose.xyz[2] - half_height == pytest.approx(TABLE_TOP, abs=0.003)
        lo, hi = _footprint(world, item)
        tables = [t for t in ("table_0", "table_1")
                  if np.all(lo >= _footprint(world, t)[0]) and np.all(hi <= _footprint(world, t)[1])]
        assert len(tables) == 1, item
        t_lo, t_hi = _footprint(world, tables[0])
        assert min(*(lo - t_lo), *(t_hi - hi)) <= 0.25, item


def test_nothing_overlaps_and_lanes_are_wide(world: World) -> None:
    """Furniture, trash boxes and the human are >= 0.9 m apart, in the room, and >= 0.9 m from the robot."""
    solid = ["table_0", "table_1", "wagon", *BOXES]
    human = world.agent("man_0")
    assert isinstance(human, Human)
    xy = np.array(human.pose.xyz[:2])
    prints = {n: _footprint(world, n) for n in solid} | {"man_0": (xy - 0.3, xy + 0.3)}
    names = list(prints)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            assert _gap(prints[a], prints[b]) >= 0.9, (a, b, _gap(prints[a], prints[b]))
        assert np.all(prints[a][0] > (-5, -2.5)) and np.all(prints[a][1] < (5, 2.5)), a
    robot = world.agent("robot_000")
    assert isinstance(robot, Robot)
    start = np.array(robot.pose.xyz[:2])
    walls = [_footprint(world, w) for w in ("wall_north", "wall_south", "wall_east", "wall_west")]
    for box in [*prints.values(), *walls]:
        assert _gap((start, start), box) >= 0.9


def test_robot_declares_drive_lidar_grippers_and_arms(world: World) -> None:
    """robot_000 declares its differential drive, its lidar on base_laser_link, two grippers and two arms."""
    robot = world.agent("robot_000")
    assert isinstance(robot, Robot) and robot.drive is not None
    assert (robot.drive.left, robot.drive.right) == ("wheel_l_joint", "wheel_r_joint")
    assert (robot.drive.radius, robot.drive.separation) == (0.1, 0.4)
    assert [lidar.link for lidar in robot.lidars] == ["base_laser_link"]
    assert {(g.part, g.side) for g in robot.grippers} == {("l_hand_link", "left"), ("r_hand_link", "right")}
    assert {(a.base, a.tip) for a in robot.arms} == {("torso_link", "l_hand_link"),
                                                     ("torso_link", "r_hand_link")}


# ---------------------------------------------------------------------------------------------- sigbot
def test_sigbot_arms_have_four_limited_revolute_joints_each() -> None:
    """Each arm chain torso -> hand has >= 4 revolute joints, each with lower < upper limits."""
    urdf = read_urdf(SIGBOT)
    for side in "lr":
        chain = [urdf.joint(n) for n in _chain(urdf, "torso_link", f"{side}_hand_link")]
        revolute = [j for j in chain if j.type == "revolute"]
        assert len(revolute) >= 4, side
        for j in revolute:
            assert j.lower is not None and j.upper is not None and j.lower < j.upper, j.name
        assert revolute[0].name == f"{side}_shoulder_pan_joint"


def test_sigbot_grippers_have_two_prismatic_fingers() -> None:
    """Each hand carries two fingers on prismatic joints with a small positive range."""
    urdf = read_urdf(SIGBOT)
    for side in "lr":
        fingers = [j for j in urdf.joints if j.parent == f"{side}_hand_link"]
        assert sorted(j.name for j in fingers) == [f"{side}_finger_1_joint", f"{side}_finger_2_joint"]
        for j in fingers:
            assert j.type == "prismatic" and j.lower == 0 and j.upper is not None and 0 < j.upper <= 0.05


def test_sigbot_wheels_drive_forward_and_match_the_drive() -> None:
    """The wheel joints are continuous about +y (positive = forward), r 0.1 m, 0.4 m apart, on the ground."""
    root = etree.parse(str(SIGBOT)).getroot()
    ys = []
    for side in "lr":
        joint = root.find(f"joint[@name='wheel_{side}_joint']")
        assert joint is not None and joint.get("type") == "continuous"
        assert joint.find("parent").get("link") == "base_link"  # type: ignore[union-attr]
        assert tuple(_floats(joint.find("axis").get("xyz"))) == (0, 1, 0)  # type: ignore[union-attr]
        xyz = _floats(joint.find("origin").get("xyz"))  # type: ignore[union-attr]
        link = root.find(f"link[@name='wheel_{side}_link']")
        assert link is not None
        radius = float(link.find("collision/geometry/cylinder").get("radius"))  # type: ignore[union-attr]
        assert radius == pytest.approx(0.1) and xyz[2] == pytest.approx(radius)  # touches z = 0
        ys.append(xyz[1])
    assert ys[0] - ys[1] == pytest.approx(0.4)


def test_sigbot_lidar_is_level_at_the_base_front() -> None:
    """base_laser_link is fixed to base_link, level, about 0.25 m high, above the base's top and in front."""
    root = etree.parse(str(SIGBOT)).getroot()
    joint = root.find("joint[@name='base_laser_joint']")
    assert joint is not None and joint.get("type") == "fixed"
    assert joint.find("parent").get("link") == "base_link"  # type: ignore[union-attr]
    origin = joint.find("origin")
    assert origin is not None
    xyz = _floats(origin.get("xyz"))
    assert np.allclose(_floats(origin.get("rpy")), 0)
    assert 0.2 <= xyz[2] <= 0.3 and xyz[0] > 0.15
    base_top = max(c[2] + h[2] for c, h in _link_boxes(root, "base_link"))
    assert base_top < xyz[2]


def _link_boxes(root: etree._Element, link: str) -> list[tuple[np.ndarray, np.ndarray]]:
    element = root.find(f"link[@name='{link}']")
    assert element is not None
    out = []
    for collision in element.findall("collision"):
        origin = collision.find("origin")
        rot = _rpy_matrix(_floats(origin.get("rpy") if origin is not None else None))
        geometry = collision.find("geometry")
        assert geometry is not None
        xyz = _floats(origin.get("xyz") if origin is not None else None)
        out.append((xyz, np.abs(rot) @ _half_extents(geometry)))
    return out


@pytest.mark.parametrize("path", URDFS, ids=[p.stem for p in URDFS])
def test_every_link_has_visual_collision_and_a_physical_inertia(path: Path) -> None:
    """Every link has visual, collision, mass > 0, a positive-definite inertia and the triangle inequality."""
    root = etree.parse(str(path)).getroot()
    assert not list(root.iter("mesh"))
    for link in root.findall("link"):
        name = link.get("name")
        assert link.find("visual") is not None and link.find("collision") is not None, name
        mass = float(link.find("inertial/mass").get("value"))  # type: ignore[union-attr]
        assert mass > 0, name
        i = link.find("inertial/inertia")
        assert i is not None, name
        tensor = np.array([[float(i.get(a, "0")) for a in row] for row in
                           (("ixx", "ixy", "ixz"), ("ixy", "iyy", "iyz"), ("ixz", "iyz", "izz"))])
        principal = np.linalg.eigvalsh(tensor)
        assert np.all(principal > 0), name
        a, b, c = principal
        assert a + b >= c * (1 - 1e-9), name


def test_generated_urdfs_are_up_to_date() -> None:
    """The URDF files are exactly what worlds/models/make_models.py generates (nobody edited them by hand)."""
    spec = importlib.util.spec_from_file_location("make_models", MODELS / "make_models.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up
    try:
        spec.loader.exec_module(module)
    finally:
        del sys.modules[spec.name]
    for name in ("sigbot", "trashbox", "table", "wagon"):
        stored = (MODELS / name / f"{name}.urdf").read_text(encoding="utf-8")
        assert getattr(module, name)().urdf() == stored, name


# ---------------------------------------------------------------------------------------------- trash boxes
def test_trashbox_opening_is_larger_than_every_trash_item(world: World) -> None:
    """The trash box's inner opening is >= 0.3 m square and wider than every trash item's largest size."""
    ox, oy = _trashbox_opening()
    assert ox >= 0.3 and oy >= 0.3
    for item in TRASH:
        obj = _obj(world, item)
        assert obj.size is not None
        largest = max(2 * obj.size[0], obj.size[1]) if obj.shape == "cylinder" else 2 * obj.size[0]
        assert largest < min(ox, oy), item


def test_trashbox_is_open_on_top_and_about_04_m_high() -> None:
    """The trash box is a floor plate and four walls about 0.4 m high; only the floor is over its centre."""
    boxes = list(_collision_boxes(TRASHBOX))
    assert len(boxes) == 5
    assert max(c[2] + h[2] for c, h in boxes) == pytest.approx(0.4, abs=0.05)
    over_centre = [c[2] + h[2] for c, h in boxes if np.all(np.abs(c[:2]) <= h[:2])]
    assert len(over_centre) == 1 and over_centre[0] <= 0.05


# ------------------------------------------------------------------------------------------- physics engines
@pytest.mark.parametrize("path", URDFS, ids=[p.stem for p in URDFS])
def test_urdfs_load_in_mujoco_and_pybullet(path: Path) -> None:
    """Every model loads in MuJoCo and in PyBullet."""
    mujoco = pytest.importorskip("mujoco")
    pybullet = pytest.importorskip("pybullet")
    assert mujoco.MjModel.from_xml_path(str(path)).ngeom > 0
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(path), physicsClientId=client)
        assert pybullet.getNumJoints(body, physicsClientId=client) == len(read_urdf(path).joints)
    finally:
        pybullet.disconnect(client)


def _sigbot_on_ground(mujoco: Any) -> tuple[Any, Any]:
    """sigbot on a free joint at z = 0 on a ground plane, casters nearly frictionless, fixed links kept."""
    spec = mujoco.MjSpec.from_file(str(SIGBOT))
    spec.compiler.fusestatic = False
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.body("base_link").add_freejoint()
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[5, 5, 0.1])
    for caster in ("caster_front_link", "caster_back_link"):
        for geom in spec.body(caster).geoms:
            geom.friction = [0.01, 0, 0]
            geom.priority = 1  # MuJoCo takes the larger friction of two geoms unless one has priority
    model = spec.compile()
    return model, mujoco.MjData(model)


def test_sigbot_stands_still_on_the_ground() -> None:
    """At z = 0 with zero controls, sigbot stays upright (< 1°) with its base at z = 0 (< 2 mm) for 3 s."""
    mujoco = pytest.importorskip("mujoco")
    model, data = _sigbot_on_ground(mujoco)
    base = model.body("base_link").id
    for _ in range(int(3.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
        assert data.xmat[base][8] > math.cos(math.radians(1.0))
        assert abs(data.xpos[base][2]) < 0.002
    assert np.linalg.norm(data.xpos[base][:2]) < 0.01


def test_sigbot_lidar_plane_is_clear_of_the_robot_within_03_m() -> None:
    """Horizontal rays from the lidar hit no other part of the robot closer than 0.29 m."""
    mujoco = pytest.importorskip("mujoco")
    model, data = _sigbot_on_ground(mujoco)
    mujoco.mj_forward(model, data)
    lidar = model.body("base_laser_link").id
    origin, rot = data.xpos[lidar].copy(), data.xmat[lidar].reshape(3, 3)
    assert rot[2, 2] == pytest.approx(1.0)
    geom = np.zeros(1, np.int32)
    for angle in np.linspace(0, 2 * math.pi, 720, endpoint=False):
        direction = rot @ np.array([math.cos(angle), math.sin(angle), 0.0])
        distance = mujoco.mj_ray(model, data, origin, direction, None, 0, lidar, geom)
        assert distance < 0 or distance >= 0.29, (math.degrees(angle), distance)


@pytest.mark.parametrize("item", TRASH)
def test_item_dropped_above_a_trashbox_lands_inside(world: World, item: str) -> None:
    """A trash item released 0.2 m above the rim, at and off the opening's centre, ends inside the box."""
    mujoco = pytest.importorskip("mujoco")
    obj = _obj(world, item)
    assert obj.size is not None
    ox, oy = _trashbox_opening()
    for dx, dy, tilt in ((0.0, 0.0, 0.0), (0.1, 0.05, 0.6), (-0.12, -0.12, 1.57)):
        spec = mujoco.MjSpec()
        spec.option.timestep = 0.002
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[2, 2, 0.1])
        child = mujoco.MjSpec.from_file(str(TRASHBOX))
        spec.attach(child, prefix="box/", frame=spec.worldbody.add_frame())
        half = obj.size[1] / 2 if obj.shape == "cylinder" else obj.size[0]
        body = spec.worldbody.add_body(pos=[dx, dy, 0.4 + 0.2 + half],
                                       quat=[math.cos(tilt / 2), math.sin(tilt / 2), 0, 0])
        body.add_freejoint()
        if obj.shape == "cylinder":
            body.add_geom(type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[obj.size[0], half, 0], mass=obj.mass)
        else:
            body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[obj.size[0], 0, 0], mass=obj.mass)
        model = spec.compile()
        data = mujoco.MjData(model)
        for _ in range(1500):
            mujoco.mj_step(model, data)
        x, y, z = data.xpos[model.nbody - 1]
        assert abs(x) < ox / 2 and abs(y) < oy / 2 and z < 0.4, (dx, dy, tilt, x, y, z)
