"""The TF tree over ROS 2 (cleanup world, paused, stepped in lockstep): every link under one root with the backend's
poses, entity frames, scans stamped with a published /clock, and the odometry's covariance."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosproc import start_sim

from sigcore.geometry import quat_conj, quat_mul, quat_rotate
from sigcore.sim.odometry_covariance import odometry_covariance
from sigcore.world import parse_world

pytestmark = pytest.mark.ros2

WORLD = Path(__file__).parent.parent.parent / "worlds" / "cleanup.xml"
SIM_WORLD = Path(__file__).parent.parent / "data" / "sim" / "world.xml"
ROBOT = "robot_000"
STRIDE, STRIDES = 50, 3  # one lidar period (10 Hz, 2 ms steps) per stride
DT_NS = 2_000_000


@pytest.fixture(scope="module")
def probe(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """The cleanup world started paused; the client moves every movable joint off zero and steps 3 x 50 steps."""
    urdf = parse_world(WORLD).urdf(ROBOT).model
    moves = ",".join(f"{j.name}={0.4 * j.upper if j.upper else 0.5:.6f}" for j in urdf.movable_joints)
    sim = start_sim(tmp_path_factory.mktemp("tf"), WORLD, "--paused")
    try:
        result = sim.client("tf.py", ROBOT, ",".join(urdf.links), moves, str(STRIDE), str(STRIDES), timeout=120)
    finally:
        sim.stop()
    assert result["set"] and result["steps"] == [1] * STRIDES, result["steps"]
    result["links"], result["root"] = urdf.links, urdf.root
    yield result


def _tree(probe: dict[str, Any]) -> dict[str, tuple[str, np.ndarray, np.ndarray]]:
    """child -> (parent, xyz, wxyz): /tf_static, then the /tf transforms stamped with the last step."""
    now = STRIDE * STRIDES * DT_NS
    tree: dict[str, tuple[str, np.ndarray, np.ndarray]] = {}
    for t, dynamic in [(t, False) for t in probe["static"]] + [(t, True) for t in probe["tf"]]:
        stamp = t["header"]["stamp"]["sec"] * 1_000_000_000 + t["header"]["stamp"]["nanosec"]
        if dynamic and stamp != now:
            continue
        child, parent = t["child_frame_id"], t["header"]["frame_id"]
        assert tree.get(child, (parent,))[0] == parent, f"frame '{child}' has two parents"
        r, q = t["transform"]["translation"], t["transform"]["rotation"]
        tree[child] = (parent, np.array([r["x"], r["y"], r["z"]]), np.array([q["w"], q["x"], q["y"], q["z"]]))
    return tree


def _in(tree: dict[str, tuple[str, np.ndarray, np.ndarray]], frame: str) -> tuple[np.ndarray, np.ndarray, str]:
    """The pose of ``frame`` in its tree's root, and that root."""
    pos, quat, seen = np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), set()
    while frame in tree:
        assert frame not in seen, f"a cycle through '{frame}'"
        seen.add(frame)
        parent, xyz, wxyz = tree[frame]
        pos, quat, frame = xyz + quat_rotate(wxyz, pos), quat_mul(wxyz, quat), parent
    return pos, quat, frame


def test_every_link_and_entity_is_in_one_tree_rooted_at_world(probe: dict[str, Any]) -> None:
    """Built from /tf_static and /tf, the tree holds every URDF link, can_0, man_0 and the scan's frame, and every
    frame's chain ends at the one root 'world'."""
    tree = _tree(probe)
    assert set(probe["links"]) <= set(tree)
    assert tree["can_0"][0] == tree["man_0"][0] == "world"
    person = parse_world(WORLD).urdf("man_0").model  # a person's REP-155 frames: <link>_man_0
    assert {f"{link}_man_0" for link in person.links if link != person.root} <= set(tree)
    assert tree["body_man_0"][0] == "man_0" and tree["l_y_hip_man_0"][0] == "body_man_0"
    unit = 1.7 / 7.5  # standing, facing -x at (4.2, 1.5): the head frame at the face, half a head radius forward
    np.testing.assert_allclose(_in(tree, "head_man_0")[0], [4.2 - unit / 4, 1.5, 1.7 - unit / 2], atol=1e-6)
    assert {_in(tree, frame)[2] for frame in tree} == {"world"}
    assert {frame for _, _, frame in probe["scans"]} == {"base_laser_link"}


def test_link_poses_relative_to_the_root_link_agree_with_the_backend(probe: dict[str, Any]) -> None:
    """Each link's position relative to base_link, composed from TF, equals the backend's within 1e-6 m (joints
    moved off zero); the entity frames are at the backend's positions."""
    tree = _tree(probe)
    base, base_q, _ = _in(tree, probe["root"])
    backend_base = np.array(probe["positions"][probe["root"]])
    backend_q = np.array(probe["rotation"])
    for link in probe["links"]:
        pos = _in(tree, link)[0]
        relative = quat_rotate(quat_conj(base_q), pos - base)
        expected = quat_rotate(quat_conj(backend_q), np.array(probe["positions"][link]) - backend_base)
        assert np.abs(relative - expected).max() < 1e-6, link
    for name, pos in probe["entities"].items():
        assert np.abs(_in(tree, name)[0] - np.array(pos)).max() < 1e-6, name


def test_a_scan_carries_the_stamp_of_a_clock_published_before_it(probe: dict[str, Any]) -> None:
    """Each scan is stamped with its step's time (10 Hz: 0.1, 0.2, 0.3 s), a /clock value that was published before
    the scan (the writers' source timestamps): a scan never runs ahead of /clock."""
    scans = probe["scans"]
    assert [stamp for stamp, _, _ in scans] == [k * STRIDE * DT_NS for k in range(1, STRIDES + 1)]
    for stamp, written, _ in scans:
        clock_written = [ts for value, ts in probe["clocks"] if value == stamp]
        assert clock_written and min(clock_written) <= written, stamp


def test_odometry_carries_the_documented_covariance(probe: dict[str, Any]) -> None:
    """The odometry's pose and twist covariance are diagonal, non-zero, and equal to odometry_covariance of the
    world's <drive> (radius 0.1 m, separation 0.4 m, 20 rad/s, no noise)."""
    pose, twist = odometry_covariance(0.1, 0.4, 20.0, 0.0)
    for got, want in ((probe["odom"]["pose"]["covariance"], pose), (probe["odom"]["twist"]["covariance"], twist)):
        matrix = np.array(got).reshape(6, 6)
        assert np.allclose(np.diag(matrix), want, rtol=1e-12) and min(want) > 0
        assert np.count_nonzero(matrix - np.diag(np.diag(matrix))) == 0


@pytest.mark.parametrize("rate", [20, 0])
def test_entity_tf_rate_sets_the_rate_of_entity_frames_and_zero_turns_them_off(tmp_path: Path, rate: int) -> None:
    """With entity_tf_rate="20" every object is on /tf every 50 ms of simulated time; with "0" none is, while the
    robot's joints and the person's frames (published with the joint states) still are."""
    text = SIM_WORLD.read_text().replace('urdf="minibot.urdf"', f'urdf="{SIM_WORLD.parent / "minibot.urdf"}"')
    world = tmp_path / "world.xml"
    world.write_text(text.replace("</world>", f'  <plugin name="ros2" entity_tf_rate="{rate}"/>\n</world>'))
    sim = start_sim(tmp_path, world, "--realtime")
    try:
        pairs = sim.client("tf_listen.py", "1.5")
    finally:
        sim.stop()
    entities = {"cube", "ball", "heavy", "wall"}
    assert "base_link wheel_l_link" in pairs and "base_link upper_arm_link" in pairs
    assert "world man" in pairs and "l_p_hip_man l_hip_man" in pairs
    assert "base_link laser_link" not in pairs  # a fixed joint: on /tf_static only
    if rate == 0:
        assert not {key.split()[1] for key in pairs} & entities
        return
    for name in entities:
        stamps = pairs[f"world {name}"]
        assert len(stamps) >= 5 and set(np.diff(stamps)) == {50_000_000}, (name, stamps)


def test_a_bad_entity_tf_rate_is_refused_at_its_attribute(tmp_path: Path) -> None:
    """entity_tf_rate="-1" is a world error at that attribute naming the valid range."""
    from sigcore_ros2.config import Ros2Config

    from sigcore.world import WorldError
    from sigcore.world.plugin_config import validate_plugin

    world = tmp_path / "world.xml"
    world.write_text('<world name="w">\n  <plugin name="ros2" entity_tf_rate="-1"/>\n</world>\n')
    parsed = parse_world(world)
    with pytest.raises(WorldError) as info:
        validate_plugin(parsed, parsed.plugins[0], Ros2Config)
    [issue] = info.value.issues
    assert issue.attribute == "entity_tf_rate"
    assert "valid: 0 <= entity_tf_rate <= 10000 [Hz]" in issue.message, issue.message
