"""The 3D scene in the browser: one viser frame node per TF frame of the scene description, the visuals as its
children, the floor, names, and the overlays (TF axes, lidar points, contacts, the map on the floor)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from sigcore.world.visuals import Visual

from .shapes import add_visual

try:  # viser's message classes: the direct path of SceneNodes.move (viser is pinned, 1.1.1)
    from viser import _messages
except ImportError:  # pragma: no cover - another viser: the public setters
    _messages = None  # type: ignore[assignment]

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation

    from .snapshot import Snapshot

ROOT = "/sigcore"
MOVED = 5e-4
"""A frame whose position [m] or quaternion changed less than this since the last update is not sent again
(0.5 mm, about 0.06 degree: not visible, and the servos' jitter stays home)."""


def node_name(i: int, parent: int) -> str:
    """The viser node of frame ``i``: under the scene's root, or under its entity's root frame ``parent``."""
    return f"{ROOT}/f{i}" if parent < 0 else f"{ROOT}/f{parent}/l{i}"


def relative(poses: np.ndarray, parent: np.ndarray) -> np.ndarray:
    """``poses`` (n, 7: xyz, wxyz in ``world``) with each frame that has a parent (``parent[i] >= 0``) expressed in
    its parent's frame instead."""
    child = np.flatnonzero(parent >= 0)
    if len(child) == 0:
        return poses
    out = poses.copy()
    p, q = poses[parent[child]], poses[child]
    conj = p[:, 3:] * np.array([1.0, -1.0, -1.0, -1.0])
    out[child, :3] = _rotate(conj, q[:, :3] - p[:, :3])
    out[child, 3:] = _multiply(conj, q[:, 3:])
    return out


def _multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise quaternion products ``a * b`` (w, x, y, z)."""
    aw, ax, ay, az = a.T
    bw, bx, by, bz = b.T
    return np.stack([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw], axis=1)


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Row-wise rotation of vectors ``v`` by unit quaternions ``q``."""
    u, w = q[:, 1:], q[:, :1]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


@dataclass
class SceneLayout:
    """The frames and visuals of one scene description (taken on the simulation thread).

    Attributes:
        frames: Every frame: each robot's link frames, each object's and human's own frame.
        parts: ``(entity, part)`` whose backend pose is each frame's pose, in the order of ``frames``.
        index: Frame name -> its index.
        visuals: ``(frame index, entity, visual)`` of every visual.
        labels: ``(frame index, entity)``: where each entity's name is shown (its root frame).
        parent: Per frame, the index of its entity's root frame (a robot's links), or -1 (a root frame).
        low, high: The corners of the box around every entity [m] (the floor and the first camera view).
    """

    frames: list[str] = field(default_factory=list)
    parts: list[tuple[str, str | None]] = field(default_factory=list)
    index: dict[str, int] = field(default_factory=dict)
    visuals: list[tuple[int, str, Visual]] = field(default_factory=list)
    labels: list[tuple[int, str]] = field(default_factory=list)
    parent: list[int] = field(default_factory=list)
    low: np.ndarray = field(default_factory=lambda: np.array([-2.0, -2.0, 0.0]))
    high: np.ndarray = field(default_factory=lambda: np.array([2.0, 2.0, 1.0]))


def layout_of(sim: Simulation | None) -> SceneLayout:
    """The layout of ``sim``'s scene now (an empty one without a world)."""
    layout = SceneLayout()
    if sim is None or not sim.worlds.loaded:
        return layout
    lows, highs = [], []
    for name, entity in sim.scene.entities.items():
        parts = sim.scene.frame_parts(name)
        first = len(layout.frames)
        root = None
        for frame, part in parts.items():
            layout.index[frame] = len(layout.frames)
            layout.frames.append(frame)
            layout.parts.append((name, part))
            if part is None:
                root = layout.index[frame]
        layout.parent.extend(-1 if i == root or root is None else root for i in range(first, len(layout.frames)))
        for visual in entity.visuals:
            if visual.frame in layout.index:
                layout.visuals.append((layout.index[visual.frame], name, visual))
        if root is not None:
            layout.labels.append((root, name))
        try:
            lo, hi = sim.scene.bounds(name)
        except Exception:  # an entity whose bounds cannot be read only leaves the floor smaller
            continue
        lows.append(lo)
        highs.append(hi)
    if lows:
        layout.low, layout.high = np.min(lows, axis=0), np.max(highs, axis=0)
    return layout


class SceneNodes:
    """The viser nodes of the scene (used by the push thread only).

    Args:
        server: The viser server.
        select: Called with an entity's name when a person clicks one of its visuals.
    """

    def __init__(self, server: Any, select: Callable[[str], None]) -> None:
        self._server = server
        self._select = select
        self._frames: list[Any] = []
        self._labels: list[Any] = []
        self._sent = np.zeros((0, 7))
        self._overlay_nodes: dict[str, Any] = {}
        self._shown: dict[str, bool] = {}
        self._camera_set = False
        self._direct = _messages is not None
        self._drawn = np.zeros(0, dtype=bool)
        self._parent = np.zeros(0, dtype=int)
        self._hidden = np.zeros(0, dtype=bool)

    def build(self, layout: SceneLayout, overlays: dict[str, bool], poses: np.ndarray | None = None) -> None:
        """Replace every node by those of ``layout``, each frame created at its pose in ``poses`` (the layout's
        frames, in ``world``) when given: a browser that connects draws every entity and name where it is from its
        first picture, not at the origin until the poses that follow arrive."""
        scene = self._server.scene
        scene.remove_by_name(ROOT)
        self._frames, self._labels = [], []
        lo, hi = layout.low, layout.high
        size = np.maximum(hi[:2] - lo[:2], 1.0) + 1.0
        centre = (lo[:2] + hi[:2]) / 2
        scene.add_grid(f"{ROOT}/floor", width=float(size[0]), height=float(size[1]), plane="xy",
                       cell_size=0.5, section_size=1.0, plane_color=(236, 233, 226), plane_opacity=1.0,
                       position=(float(centre[0]), float(centre[1]), -0.001))
        self._parent = np.array(layout.parent, dtype=int)
        names = [node_name(i, p) for i, p in enumerate(layout.parent)]
        at = relative(poses, self._parent) if poses is not None and len(poses) == len(names) else None
        handles: dict[int, Any] = {}
        for i in sorted(range(len(names)), key=lambda i: layout.parent[i] >= 0):  # roots first, then their links
            pose = {} if at is None else {"position": tuple(at[i, :3].tolist()), "wxyz": tuple(at[i, 3:].tolist())}
            handles[i] = scene.add_frame(names[i], show_axes=overlays["frames"], axes_length=0.12,
                                         axes_radius=0.006, **pose)
        self._frames = [handles[i] for i in range(len(names))]
        for j, (i, entity, visual) in enumerate(layout.visuals):
            for handle in add_visual(scene, f"{names[i]}/v{j}", visual):
                handle.on_click(lambda _event, name=entity: self._select(name))
        for i, entity in layout.labels:
            self._labels.append(scene.add_label(f"{names[i]}/name", entity, position=(0.0, 0.0, 0.12),
                                                anchor="bottom-center", visible=overlays["names"]))
        self._sent = np.full((len(layout.frames), 7), np.inf) if at is None else at.copy()
        self._drawn = np.zeros(len(layout.frames), dtype=bool)  # frames with a visual or a name
        self._drawn[[i for i, _, _ in layout.visuals] + [i for i, _ in layout.labels]] = True
        self._hidden = np.zeros(len(layout.frames), dtype=bool)
        self._shown = {"names": overlays["names"], "frames": overlays["frames"]}
        for node in self._overlay_nodes.values():
            node.remove()
        self._overlay_nodes = {}
        if not self._camera_set and layout.frames:
            self._camera_set = True
            camera = self._server.initial_camera
            extent = float(max(size))
            look = np.array([centre[0] + 0.1 * extent, centre[1] + 0.05 * extent, 0.0])  # the panel is right
            camera.position = tuple(look + np.array([0.0, -0.42 * extent, 0.62 * extent]))
            camera.look_at = tuple(look)
            camera.up = (0.0, 0.0, 1.0)

    def move(self, poses: np.ndarray, every_frame: bool = False, exact: bool = False) -> None:
        """Send the frames that moved: their position, their orientation or both, whichever changed by more than
        :data:`MOVED` (``exact``: by anything at all, so that the scene shows the poses exactly: a recording paused or
        scrubbed); frames without a visual or a name only when ``every_frame`` (the TF overlay shows them). A
        robot's links are nodes under its root link, posed relative to it: a robot that drives moves one node.

        The direct path hands viser its messages itself (which frames changed is already known here): a third of
        the push thread's time; any other viser than the pinned one gets its public setters."""
        if len(poses) != len(self._frames):
            return
        poses = relative(poses, self._parent)
        changed = poses != self._sent if exact else np.abs(poses - self._sent) > MOVED
        if not every_frame:
            changed &= self._drawn[:, None]
        moved_at = np.flatnonzero(changed[:, :3].any(axis=1)).tolist()
        turned = np.flatnonzero(changed[:, 3:].any(axis=1)).tolist()
        if self._direct:
            try:
                for i in moved_at:
                    impl = self._frames[i]._impl
                    row = poses[i, :3].tolist()
                    impl.position[:] = row
                    impl.api._queue_scene_message(_messages.SetPositionMessage(impl.name, tuple(row)))
                for i in turned:
                    impl = self._frames[i]._impl
                    row = poses[i, 3:].tolist()
                    impl.wxyz[:] = row
                    impl.api._queue_scene_message(_messages.SetOrientationMessage(impl.name, tuple(row)))
            except AttributeError:  # another viser than the one pinned: its public setters from now on
                self._direct = False
        if not self._direct:
            for i in moved_at:
                self._frames[i].position = poses[i, :3]
            for i in turned:
                self._frames[i].wxyz = poses[i, 3:]
        self._sent[moved_at, :3] = poses[moved_at, :3]
        self._sent[turned, 3:] = poses[turned, 3:]

    def hide(self, hidden: np.ndarray | None) -> None:
        """Hide the frames ``hidden`` says (with their visuals and names; a recording's entity that was not in the
        world at that moment) and show the others again; None: nothing changes."""
        if hidden is None or len(hidden) != len(self._frames):
            return
        for i in np.flatnonzero(hidden != self._hidden).tolist():
            self._frames[i].visible = not bool(hidden[i])
        self._hidden = np.array(hidden, dtype=bool)

    def overlays(self, snap: Snapshot, overlays: dict[str, bool]) -> None:
        """Show or hide names and TF axes; the lidar points, contacts, the map and nothing else."""
        if self._shown.get("names") != overlays["names"]:
            for label in self._labels:
                label.visible = overlays["names"]
            self._shown["names"] = overlays["names"]
        if self._shown.get("frames") != overlays["frames"]:
            for frame in self._frames:
                frame.show_axes = overlays["frames"]
            self._shown["frames"] = overlays["frames"]
        self._points("scan", snap.scan, (0, 160, 255), 0.03)
        self._points("contacts", snap.contacts, (230, 20, 20), 0.06)
        if snap.grid is not None:
            image, width, height, centre, quat = snap.grid
            old = self._overlay_nodes.pop("map", None)
            if old is not None:
                old.remove()
            if image.size:  # an empty image: no map (a recording before its first map)
                self._overlay_nodes["map"] = self._server.scene.add_image(
                    "/sigcore_map", image, width, height, position=centre, wxyz=quat, visible=overlays["map"],
                    cast_shadow=False, receive_shadow=False)
        elif "map" in self._overlay_nodes:
            self._overlay_nodes["map"].visible = overlays["map"]

    def _points(self, key: str, points: np.ndarray | None, color: tuple[int, int, int], size: float) -> None:
        node = self._overlay_nodes.pop(key, None)
        if node is not None:
            node.remove()
        if points is not None and len(points) > 0:
            self._overlay_nodes[key] = self._server.scene.add_point_cloud(
                f"/sigcore_{key}", points.astype(np.float32), color, point_size=size, point_shape="circle")
