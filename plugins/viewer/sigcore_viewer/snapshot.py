"""Scene snapshots: what the browser shows at one moment (:class:`Snapshot`), the viewer's process's report of one
handed to viser (:class:`Pushed`), and the taking of a running simulation's snapshots on its thread between two steps
(:class:`LiveSnapshots`: every frame's pose read from the backend, the run's line, the texts of the publications a
viewer shows, the selected entity's state, the overlays' geometry and new camera images).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from sigcore.agent.exceptions import ApiError
from sigcore.agent.robot import RobotObj
from sigcore.geometry import quat_yaw
from sigcore.publish import Publication, PublicationSink
from sigcore.text import quote

from .commands import pace_name
from .overlays import contact_points, grid_image, scan_points
from .scenebuild import SceneLayout, layout_of

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation

UNLOADED = (-1, -1)
"""The layout key while no world is loaded."""


@dataclass
class Snapshot:
    """What the browser shows at one moment, taken on the simulation thread between two steps.

    Attributes:
        step: The step the poses belong to (``sim.worlds.elapsed_steps``).
        time: Its simulated time [s] (of the loaded world).
        wall: ``time.perf_counter()`` when it was taken [s].
        layout: The scene's frames and visuals when they changed (a spawn, a delete, another world), else None.
        poses: (frames, 7) position [m] and quaternion (w, x, y, z) of every frame of the layout, in its order.
        status: The run's line (time, wall time, real-time factor, state).
        texts: The panel's other texts by key (score lines, events, result, selection, notes).
        agents: The agents a message may go to; entities: those that can be selected.
        scan: (n, 3) lidar hit points in ``world`` [m], or None when the overlay is off.
        contacts: (n, 3) contact markers [m], or None when the overlay is off.
        grid: ``(image (h, w, 3) uint8, width [m], height [m], centre xyz, wxyz)`` of the newest map, or None.
        images: Camera images by topic (h, w, 3) uint8, new since the last snapshot.
        pace: The run's pace (a name of :data:`~sigcore_viewer.commands.PACES`).
        exact: Send every frame whose pose changed at all (a recording paused or scrubbed: the scene shows the
            moment exactly), not only those that moved more than :data:`~sigcore_viewer.scenebuild.MOVED`.
        hidden: (frames,) frames to hide (a recording's entity not in the world at that moment), or None.
        timeline: A recording's ``(time [s], playing, speed name)``, or None for a live run.
        ended: The run has ended (:meth:`~sigcore_viewer.viewer.WebViewer.linger`): the page holds its last
            moment, the run's controls are disabled, and ``texts["table"]`` holds the features' report (the
            referee's score table).
    """

    step: int
    time: float
    wall: float
    layout: SceneLayout | None
    poses: np.ndarray
    status: str
    texts: dict[str, str]
    agents: list[str]
    entities: list[str]
    scan: np.ndarray | None = None
    contacts: np.ndarray | None = None
    grid: tuple[np.ndarray, float, float, np.ndarray, np.ndarray] | None = None
    images: dict[str, np.ndarray] = field(default_factory=dict)
    pace: str = "real time"
    exact: bool = False
    hidden: np.ndarray | None = None
    timeline: tuple[float, bool, str] | None = None
    ended: bool = False


@dataclass(frozen=True)
class Pushed:
    """The viewer's process handed a snapshot to viser, which sends it to the browsers.

    Attributes:
        step: The snapshot's step.
        taken: When it was taken (:attr:`Snapshot.wall`, ``time.perf_counter()`` of the simulation's process) [s].
        handed: When it was handed to viser, on the same clock (``perf_counter`` is the machine's monotonic clock,
            shared by its processes) [s].
    """

    step: int
    taken: float
    handed: float


class Displays(PublicationSink):
    """The publications a viewer shows, as they arrive (on the simulation thread): those with a ``display`` hint,
    laser scans, occupancy grids and images. It never names who declared them."""

    LOG_LINES = 200

    def __init__(self) -> None:
        self.values: dict[str, str] = {}
        self.log: list[str] = []
        self.results: dict[str, str] = {}
        self.scans: dict[str, dict[str, Any]] = {}
        self.grid: dict[str, Any] | None = None
        self.grid_version = 0
        self.images: dict[str, dict[str, Any]] = {}
        self.image_versions: dict[str, int] = {}  # never reset: a new image always has a new number

    def declare(self, publication: Publication) -> None:
        pass

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        kind = publication.msg_type
        if publication.display is not None:
            text = publication.display_text(value)
            if publication.display == "value":
                self.values[publication.topic] = text
            elif publication.display == "log":
                self.log.append(text)
                del self.log[:-self.LOG_LINES]
            else:
                self.results[publication.topic] = text
        elif kind == "sensor_msgs/msg/LaserScan":
            self.scans[publication.topic] = value
        elif kind == "nav_msgs/msg/OccupancyGrid":
            self.grid = value
            self.grid_version += 1
        elif kind == "sensor_msgs/msg/Image":
            self.images[publication.topic] = value
            self.image_versions[publication.topic] = self.image_versions.get(publication.topic, 0) + 1

    def withdraw(self, publication: Publication) -> None:
        topic = publication.topic
        for store in (self.values, self.results, self.scans, self.images):
            store.pop(topic, None)

    def restart(self) -> None:
        """The world was reset: the old trial's events and result are no longer shown."""
        self.log.clear()
        self.results.clear()

    def clear(self) -> None:
        """A new world: nothing of the old one is shown."""
        self.values.clear()
        self.log.clear()
        self.results.clear()
        self.scans.clear()
        self.images.clear()
        self.grid = None
        self.grid_version += 1


class LiveSnapshots:
    """The snapshots of a running simulation: what the last one sent (the layout, the map's and each image's
    version) so that the next carries only what changed, and the recent real-time factor.

    Attributes:
        displays: The publications shown (connected to the simulation's publications by the viewer).
        wall0: ``time.perf_counter()`` when the run started showing [s] (the run's line counts wall time from it).
    """

    def __init__(self) -> None:
        self.displays = Displays()
        self.wall0 = 0.0
        self._layout: SceneLayout | None = None
        self._layout_key: tuple[int, int] | None = None
        self._rtf_window: list[tuple[float, float]] = []  # (wall, elapsed sim time) of recent snapshots
        self._grid_sent = -1
        self._images_sent: dict[str, int] = {}

    def take(self, sim: Simulation, selected: str | None, notes: list[str], overlays: dict[str, bool],
             force_layout: bool = False) -> Snapshot:
        """The snapshot of ``sim`` now, with ``selected``'s state, the ``notes`` and the overlays that are on; it
        carries the layout when it changed (or ``force_layout``), the map and images when new."""
        wall = time.perf_counter()
        layout = None
        if not sim.worlds.loaded:
            if force_layout or self._layout_key != UNLOADED or self._layout is None:  # once, not at every update
                self._layout, self._layout_key = layout_of(None), UNLOADED
                layout = self._layout
        else:
            key = (id(sim.scene), sim.scene.version)
            if force_layout or key != self._layout_key or self._layout is None:
                self._layout, self._layout_key = layout_of(sim), key
                layout = self._layout
        assert self._layout is not None
        poses = sim.backend.get_poses(self._layout.parts) if sim.worlds.loaded else np.empty((0, 7))
        control = sim.control
        self._rtf_window.append((wall, sim.worlds.elapsed_time))
        while len(self._rtf_window) > 2 and wall - self._rtf_window[0][0] > 2.0:
            self._rtf_window.pop(0)
        (w0, t0), (w1, t1) = self._rtf_window[0], self._rtf_window[-1]
        rtf = (t1 - t0) / (w1 - w0) if w1 - w0 > 0.2 else float("nan")
        state = ("no world loaded" if not sim.worlds.loaded else "stopping" if control.stopping else
                 "paused" if control.paused else
                 f"running ({pace_name(control.realtime_factor)})")
        rtf_text = "–" if math.isnan(rtf) else f"{rtf:.2f}"
        status = (f"**{state}** · world `{sim.world.name}` · t = {sim.time:.2f} s · step {sim.step_count} · "
                  f"wall {wall - self.wall0:.1f} s · real-time factor {rtf_text}")
        d = self.displays
        texts = {
            "score": "  \n".join(d.values.values()) or "no score in this world",
            "events": "  \n".join(reversed(d.log[-15:])) or "no events yet",
            "result": "  \n".join(d.results.values()),
            "selection": describe(sim, selected),
            "notes": "  \n".join(reversed(notes)),
        }
        snap = Snapshot(sim.worlds.elapsed_steps, sim.time, wall, layout, poses, status, texts,
                        list(sim.entities) if sim.worlds.loaded else [],
                        list(sim.entities.names) if sim.worlds.loaded else [], pace=pace_name(control.realtime_factor))
        if sim.worlds.loaded:
            if overlays["scan"]:
                snap.scan = scan_points(self._layout, d.scans.values(), poses)
            if overlays["contacts"]:
                snap.contacts = contact_points(sim)
            if d.grid is not None and d.grid_version != self._grid_sent:
                snap.grid = grid_image(d.grid)
                self._grid_sent = d.grid_version
            for topic, value in d.images.items():
                if self._images_sent.get(topic) != d.image_versions[topic]:
                    self._images_sent[topic] = d.image_versions[topic]
                    image = camera_image(value)
                    if image is not None:
                        snap.images[topic] = image
        return snap


def describe(sim: Simulation, name: str | None) -> str:
    """The state of the selected entity (pose, velocity, tags, who grasps it, joint angles)."""
    if name is None:
        return "click an entity, or pick one above"
    if not sim.worlds.loaded or name not in sim.entities:
        return f"{quote(name)} is gone (deleted, or another world)"
    handle = sim.entities[name]
    lines = [f"**{name}** ({handle.kind})"]
    try:
        pos, quat = sim.backend.get_pose(name)
        lines.append(f"position: {pos[0]:.3f} {pos[1]:.3f} {pos[2]:.3f} m")
        w, x, y, z = quat
        yaw = math.degrees(quat_yaw(quat))
        lines.append(f"orientation (w x y z): {w:.3f} {x:.3f} {y:.3f} {z:.3f} (yaw {yaw:.1f}°)")
        v = handle.velocity()
        lines.append(f"velocity: {v[0]:.3f} {v[1]:.3f} {v[2]:.3f} m/s")
    except ApiError:
        pass
    info = sim.entities.info.get(name) if name in sim.entities.info.names else None
    if info is not None:
        lines.append(f"category: {info.category}; tags: {', '.join(info.tags) or 'none'}")
    held = sim.entities.grasps.held_by(name)
    if held is not None:
        lines.append(f"grasped by: {held[0]} ({held[1]})")
    holding = [f"{obj} in {part}" for robot, part, obj in sim.entities.grasps.items() if robot == name]
    if holding:
        lines.append(f"holding: {', '.join(holding)}")
    if isinstance(handle, RobotObj):
        angles = handle.all_joint_angles()
        if angles:
            lines.append("joints [rad]: " + ", ".join(f"{j} {a:.2f}" for j, a in angles.items()))
    return "  \n".join(lines)


def camera_image(value: dict[str, Any]) -> np.ndarray | None:
    """A ``sensor_msgs/Image`` (rgb8, bgr8, mono8 or 32FC1 depth) as an RGB array; None for other encodings."""
    h, w, encoding = int(value.get("height", 0)), int(value.get("width", 0)), str(value.get("encoding", ""))
    data = value.get("data")
    if h <= 0 or w <= 0 or data is None:
        return None
    raw = np.frombuffer(bytes(data) if not isinstance(data, np.ndarray) else data.tobytes(), dtype=np.uint8)
    if encoding in ("rgb8", "bgr8") and raw.size == h * w * 3:
        image = raw.reshape(h, w, 3)
        return image[:, :, ::-1] if encoding == "bgr8" else image
    if encoding == "mono8" and raw.size == h * w:
        return np.repeat(raw.reshape(h, w, 1), 3, axis=2)
    if encoding == "32FC1" and raw.size == h * w * 4:
        depth = raw.view(np.float32).reshape(h, w)
        finite = np.isfinite(depth)
        top = float(depth[finite].max()) if finite.any() else 1.0
        gray = np.where(finite, 255 - np.clip(depth / max(top, 1e-6), 0, 1) * 255, 0).astype(np.uint8)
        return np.repeat(gray[:, :, None], 3, axis=2)
    return None
