"""The viewer's overlays, in-process without a browser: lidar points, contact markers, the map on the floor, camera
images; each from the core's contracts (publications, contacts, the scene's frames), in lockstep."""

from __future__ import annotations

import socket
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from sigcore_viewer.snapshot import Pushed, Snapshot
from sigcore_viewer.viewer import WebViewer

from sigcore.geometry import quat_to_matrix
from sigcore.publish import Publication
from sigcore.sim import Simulation
from sigcore.world import parse_world

CLEANUP = Path(__file__).resolve().parents[2] / "worlds" / "cleanup.xml"
TIMEOUT = 10.0
"""Wall seconds a snapshot may take to be pushed (milliseconds here; generous for a loaded CI)."""


class Taken(list[Snapshot]):
    """The snapshots a viewer took, and the reports of those its process handed to viser."""

    def __init__(self, viewer: WebViewer) -> None:
        super().__init__()
        self.reports: list[Pushed] = []
        viewer.snapshot_observers.append(self.append)
        viewer.push_observers.append(self.reports.append)


@pytest.fixture
def started() -> Iterator[tuple[Simulation, WebViewer, Taken]]:
    sim = Simulation(parse_world(CLEANUP), "mujoco")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    viewer = WebViewer(port=port)
    pushed = Taken(viewer)
    viewer.open()
    viewer.start(sim)
    try:
        yield sim, viewer, pushed
    finally:
        viewer.stop()


def fresh(viewer: WebViewer, pushed: Taken) -> Snapshot:
    """Service the viewer until a snapshot taken from now on was pushed by the viewer's process; the first one
    taken from now on (a later one does not repeat what it already showed: a map, an image)."""
    since = time.perf_counter()
    viewer.set_overlay("names", True)  # forces the next snapshot at once
    deadline = since + TIMEOUT
    while time.perf_counter() < deadline:
        viewer.service(0.0)
        if any(report.taken >= since for report in pushed.reports):
            return next(snap for snap in pushed if snap.wall >= since)
        time.sleep(0.002)
    raise AssertionError(f"no snapshot within {TIMEOUT} s")


def test_lidar_points_lie_on_the_room_around_the_robot(started: tuple[Simulation, WebViewer, Taken]) -> None:
    sim, viewer, pushed = started
    assert fresh(viewer, pushed).scan is None  # off by default: nothing computed
    viewer.set_overlay("scan", True)
    sim.step(500)  # 1 s: the robot has settled on its wheels; a scan every 50 steps (10 Hz at 2 ms)
    points = fresh(viewer, pushed).scan
    assert points is not None and len(points) > 300  # 360 beams, nearly all hit something in a closed room
    # every hit lies in the room (walls' inner faces at x = +-5, y = +-2.5), near the lidar's height (0.25 m; the
    # robot rests pitched by about half a degree on its casters, so 9 m ahead the plane is 0.1 m higher)
    assert np.all(np.abs(points[:, 0]) <= 5.0 + 1e-3) and np.all(np.abs(points[:, 1]) <= 2.5 + 1e-3)
    assert np.all((points[:, 2] > 0.15) & (points[:, 2] < 0.40))
    # the beams straight behind and ahead of the robot (at x = -4, facing +x) hit the west and the east wall
    axis = points[np.abs(points[:, 1]) < 0.05]
    assert np.isclose(axis[:, 0].min(), -5.0, atol=0.01) and np.isclose(axis[:, 0].max(), 5.0, atol=0.01)


def test_contacts_mark_the_parts_that_touch(started: tuple[Simulation, WebViewer, Taken]) -> None:
    sim, viewer, pushed = started
    viewer.set_overlay("contacts", True)
    sim.step(50)  # the items settle on the tables
    markers = fresh(viewer, pushed).contacts
    assert markers is not None
    can = np.asarray(sim.backend.get_pose("can_0")[0])
    assert np.min(np.linalg.norm(markers - can, axis=1)) < 1e-9  # the can touches table_0
    wheels = [np.asarray(sim.backend.get_pose("robot_000", part)[0])
              for part in sim.entities.rolling_parts("robot_000")]
    for wheel in wheels:  # rolling on the floor is no contact worth a marker
        assert np.min(np.linalg.norm(markers - wheel, axis=1)) > 1e-6


def test_an_occupancy_grid_lies_on_the_floor(started: tuple[Simulation, WebViewer, Taken]) -> None:
    sim, viewer, pushed = started
    grid = sim.publications.declare(Publication("/map", "nav_msgs/msg/OccupancyGrid", "latched", origin="test"))
    cells = np.full((4, 6), -1, dtype=np.int8)  # 4 rows (y) x 6 columns (x), 0.5 m cells
    cells[0, 0], cells[3, 5] = 100, 0
    grid.publish({"info": {"resolution": 0.5, "width": 6, "height": 4,
                           "origin": {"position": {"x": -1.0, "y": -2.0, "z": 0.0},
                                      "orientation": {"w": 1.0, "x": 0.0, "y": 0.0, "z": 0.0}}},
                  "data": cells.ravel().tolist()})
    snap = fresh(viewer, pushed)
    assert snap.grid is not None
    image, width, height, centre, _ = snap.grid
    assert (width, height) == (3.0, 2.0) and image.shape == (4, 6, 3)
    np.testing.assert_allclose(centre[:2], [0.5, -1.0])  # origin + half the extent
    assert tuple(image[3, 0]) == (0, 0, 0)  # occupied cell (row 0 of the grid: bottom of the picture)
    assert tuple(image[0, 5]) == (255, 255, 255)  # free
    assert tuple(image[1, 1]) == (200, 200, 200)  # unknown


@pytest.mark.slow
def test_a_camera_image_is_shown(started: tuple[Simulation, WebViewer, Taken]) -> None:
    sim, viewer, pushed = started
    camera = sim.publications.declare(Publication("/robot_000/head/image", "sensor_msgs/msg/Image", "sensor",
                                                  origin="test"))
    rgb = np.zeros((2, 3, 3), dtype=np.uint8)
    rgb[0, 0] = (255, 0, 0)
    for encoding, data in (("rgb8", rgb), ("bgr8", rgb[:, :, ::-1].copy())):
        camera.publish({"height": 2, "width": 3, "encoding": encoding, "data": data.tobytes()})
        image = fresh(viewer, pushed).images["/robot_000/head/image"]
        assert image.shape == (2, 3, 3) and tuple(image[0, 0]) == (255, 0, 0)
    camera.publish({"height": 2, "width": 3, "encoding": "yuv422", "data": b"\0" * 12})
    assert "/robot_000/head/image" not in fresh(viewer, pushed).images  # an encoding it cannot show: nothing


def test_the_head_camera_of_the_clean_up_robot_is_shown(started: tuple[Simulation, WebViewer, Taken]) -> None:
    """robot_000's RGB-D head camera (15 Hz): after 100 steps its colour and depth images reach the viewer (the
    viewer takes images, so the camera renders with no other subscriber), at the camera's size."""
    sim, viewer, pushed = started
    sim.step(100)
    sim.cameras.settle()
    images = fresh(viewer, pushed).images
    assert images["/robot_000/head_rgbd/image_raw"].shape == (240, 320, 3)
    assert images["/robot_000/head_rgbd/depth/image_raw"].shape == (240, 320, 3)  # depth shown in grey levels
    assert images["/robot_000/head_rgbd/image_raw"].std() > 5  # the room, not a blank picture


@pytest.mark.slow
def test_robot_links_are_nested_under_the_robot_and_compose_to_their_pose(
        started: tuple[Simulation, WebViewer, Taken]) -> None:
    """A robot's link nodes hang under its root link's node, posed relative to it (one node moves when it drives);
    composed, every drawn link is where the backend has it, within the viewer's send threshold (0.5 mm)."""
    sim, viewer, pushed = started
    sim.robot("robot_000").set_wheel_velocity(3.0, 2.0)  # drive and turn
    sim.step(400)
    layout = next(s.layout for s in [fresh(viewer, pushed), *reversed(pushed)] if s.layout is not None)
    root = layout.parts.index(("robot_000", None))
    base = viewer.node_pose(f"/sigcore/f{root}")  # what viser sends the browsers, in the viewer's process
    assert base is not None
    base_position, base_wxyz = np.array(base[0]), np.array(base[1])
    checked = 0
    for j, (entity, part) in enumerate(layout.parts):
        if entity != "robot_000" or part is None or j not in {i for i, _, _ in layout.visuals}:
            continue
        node = viewer.node_pose(f"/sigcore/f{root}/l{j}")
        assert node is not None and layout.parent[j] == root
        position = base_position + quat_to_matrix(base_wxyz) @ np.array(node[0])
        np.testing.assert_allclose(position, sim.backend.get_pose("robot_000", part)[0], atol=2e-3)
        checked += 1
    assert checked >= 10  # sigbot's drawn links
    assert np.linalg.norm(base_position[:2] - np.array([-4.0, 0.0])) > 0.1  # it did drive


def test_meshes_and_primitives_become_viser_nodes(tmp_path: Path) -> None:
    """Every shape of the scene description becomes nodes: a box, a sphere, a cylinder, a capsule (cylinder and two
    end spheres) and a mesh read with trimesh (its vertices scaled); an unreadable mesh is left out, not an error."""
    import viser
    from sigcore_viewer.shapes import add_visual

    from sigcore.world.visuals import Visual

    mug = Path(__file__).resolve().parents[1] / "data" / "worlds" / "models" / "mug.obj"
    broken = tmp_path / "broken.obj"
    broken.write_text("this is not a mesh\n")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    try:
        one = (1.0, 0.0, 0.0, 0.0)
        made = {shape: add_visual(server.scene, f"/t/{shape}", Visual("f", shape, size, (0.0, 0.0, 0.0), one,
                                                                       (1.0, 0.0, 0.0, 1.0), mesh))
                for shape, size, mesh in (("box", (1.0, 2.0, 3.0), None), ("sphere", (0.5,), None),
                                          ("cylinder", (0.1, 0.4), None), ("capsule", (0.1, 0.4), None),
                                          ("mesh", (2.0, 2.0, 2.0), mug))}
        assert {k: len(v) for k, v in made.items()} == {"box": 1, "sphere": 1, "cylinder": 1, "capsule": 3,
                                                          "mesh": 1}
        ends = sorted(float(h.position[2]) for h in made["capsule"][1:])
        assert ends == pytest.approx([-0.2, 0.2])  # the end spheres at the ends of the cylinder, along z
        import trimesh

        loaded: Any = trimesh.load(str(mug), force="mesh")
        vertices = np.asarray(loaded.vertices)
        np.testing.assert_allclose(made["mesh"][0].vertices, vertices * 2.0, rtol=1e-5, atol=1e-6)
        assert add_visual(server.scene, "/t/broken", Visual("f", "mesh", (1.0, 1.0, 1.0), (0.0, 0.0, 0.0), one,
                                                            (1.0, 1.0, 1.0, 1.0), broken)) == []
    finally:
        server.stop()
