"""The web viewer: a :class:`sigcore.viewer.Viewer` serving the world live to any browser through viser.

Three threads, each with its own job:

* the **simulation thread** calls :meth:`WebViewer.service` between steps. It runs the person's commands (queued by
  the browser callbacks) and, at most ``rate`` times a second of wall time, takes a :class:`Snapshot`: every frame's
  pose read from the backend, the run's state, the texts to show. Nothing else of the viewer touches the
  simulation;
* the **push thread** turns the newest snapshot into viser updates (only what changed is sent); a snapshot it had no
  time for is replaced by the next one, so a slow browser never slows the simulation;
* **viser's threads** serve the page and call the GUI callbacks, which only queue commands.
"""

from __future__ import annotations

import contextlib
import io
import logging
import math
import queue
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from sigcore.agent.exceptions import ApiError
from sigcore.agent.robot import RobotObj
from sigcore.api.call import call
from sigcore.geometry import quat_to_matrix, quat_yaw
from sigcore.publish import Publication, PublicationSink
from sigcore.text import clip, quote
from sigcore.viewer import DEFAULT_PORT, VIEWER_SENDER, Viewer, ViewerError
from sigcore.world.models import Object

from .panel import Panel
from .scenebuild import SceneLayout, SceneNodes, layout_of

if TYPE_CHECKING:
    from sigcore.sim.simulation import Simulation

log = logging.getLogger("sigcore.viewer")

Command = Callable[["Simulation"], "str | None"]
"""What a person asked, run on the simulation thread between steps; returns a note to show, or None."""

PACES: dict[str, float | None] = {"real time": 1.0, "0.25x": 0.25, "0.5x": 0.5, "2x": 2.0, "5x": 5.0,
                                  "10x": 10.0, "as fast as possible": None}
"""The paces a person may pick (simulated seconds per wall second; None: as fast as possible)."""


def pace_name(factor: float | None) -> str:
    """The name of ``factor`` among :data:`PACES`, or ``"<f>x"``."""
    for name, value in PACES.items():
        if value == factor:
            return name
    return f"{factor:g}x"


@dataclass
class Snapshot:
    """What the browser shows at one moment, taken on the simulation thread between two steps.

    Attributes:
        step: The step the poses belong to (``sim.elapsed_steps``).
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


class _Displays(PublicationSink):
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


class WebViewer(Viewer):
    """The browser viewer (viser). See :class:`sigcore.viewer.Viewer` for the arguments."""

    name = "web"

    def __init__(self, host: str = "127.0.0.1", port: int | None = None, rate: float = 30.0) -> None:
        super().__init__(host, port, rate)
        self._server: Any = None
        self._sim: Simulation | None = None
        # queue.Queue, not SimpleQueue: SimpleQueue.get(timeout=...) on the main thread can block for good when a
        # signal (Ctrl-C, SIGTERM) arrives during the wait (seen with CPython 3.11); Queue waits on a Condition
        self._commands: queue.Queue[Command] = queue.Queue()
        self._displays = _Displays()
        self._layout: SceneLayout | None = None
        self._layout_key: tuple[int, int] | None = None
        self._next_snapshot = 0.0
        self._selected: str | None = None
        self._notes: list[str] = []
        self._overlays = {"names": True, "frames": False, "scan": False, "contacts": False, "map": True}
        self._rtf_window: list[tuple[float, float]] = []  # (wall, elapsed sim time) of recent snapshots
        self._wall0 = 0.0
        self._grid_sent = -1
        self._images_sent: dict[str, int] = {}
        self._mailbox: Snapshot | None = None
        self._wake = threading.Condition()
        self._stopping = False
        self._pusher: threading.Thread | None = None
        self._panel: Panel | None = None
        self._nodes: SceneNodes | None = None
        self.pushed = 0
        """Snapshots the push thread has sent to viser (for tests and the bench)."""
        self.push_failures = 0
        """Snapshots the push thread failed to send (logged: the first, then every 100th)."""
        self.push_observers: list[Callable[[Snapshot], None]] = []
        """Called on the push thread once each snapshot was handed to viser, which sends it to the browsers (the
        bench measures the latency with it)."""

    # ------------------------------------------------------------------ the server
    @property
    def url(self) -> str:
        if self._server is None:
            raise ViewerError("the viewer is not open yet (open() or start())")
        host = "127.0.0.1" if self.host in ("0.0.0.0", "") else self.host
        return f"http://{host}:{self._server.get_port()}"

    def open(self) -> None:
        """Listen on the port (the next free one from 8080 when none was given); :attr:`url` is known after.

        Raises:
            ViewerError: the port given is taken, or no port from 8080 to 8179 is free.
        """
        if self._server is not None:
            return
        if self.port is not None:
            if not _free(self.host, self.port):
                raise ViewerError(f"port {self.port} on {self.host} is in use by another program; choose another "
                                  f"--viewer-port, or leave it out to take the next free port from {DEFAULT_PORT}")
            port = self.port
        else:
            found = next((p for p in range(DEFAULT_PORT, DEFAULT_PORT + 100) if _free(self.host, p)), None)
            if found is None:
                raise ViewerError(f"no free port from {DEFAULT_PORT} to {DEFAULT_PORT + 99} on {self.host}; "
                                  "give one with --viewer-port")
            port = found
            if port != DEFAULT_PORT:
                log.warning("viewer: port %d is in use; the viewer listens on port %d", DEFAULT_PORT, port)
        import viser

        logging.getLogger("websockets").setLevel(logging.CRITICAL)  # a connection that is no websocket (a probe)
        with contextlib.redirect_stdout(io.StringIO()):  # viser prints its own banner; sigcore says the URL
            self._server = viser.ViserServer(host=self.host, port=port, label="sigcore", verbose=False)
        if self._server.get_port() != port:
            log.warning("viewer: port %d was taken meanwhile; the viewer listens on port %d", port,
                        self._server.get_port())

    def start(self, sim: Simulation) -> None:
        self.open()
        self._sim = sim
        self._wall0 = time.perf_counter()
        server = self._server
        server.scene.set_up_direction("+z")
        self._nodes = SceneNodes(server, self._post_select)
        self._panel = Panel(server, self._post, self._overlays)
        self._panel.bind(self._post_select, self._post_move)
        sim.publications.connect(self._displays)
        sim.world_observers.append(self._world_changed)
        sim.reset_observers.append(self._displays.restart)
        self._stopping = False
        self._pusher = threading.Thread(target=self._push_loop, name="sigcore-viewer-push", daemon=True)
        self._pusher.start()
        self._snapshot(force_layout=True)

    def stop(self) -> None:
        sim = self._sim
        if sim is not None:
            sim.publications.disconnect(self._displays)
            if self._world_changed in sim.world_observers:
                sim.world_observers.remove(self._world_changed)
            if self._displays.restart in sim.reset_observers:
                sim.reset_observers.remove(self._displays.restart)
            self._sim = None  # service() after stop() does nothing
        with self._wake:
            self._stopping = True
            self._wake.notify_all()
        if self._pusher is not None:
            self._pusher.join(timeout=5.0)
            self._pusher = None
        if self._server is not None:
            try:
                with contextlib.redirect_stdout(io.StringIO()):
                    self._server.stop()
            except Exception:  # viser's own shutdown; the run's results matter more
                log.debug("viewer: stopping viser raised", exc_info=True)
            self._server = None

    # ------------------------------------------------------------------ the simulation thread
    def service(self, timeout: float) -> None:
        sim = self._sim
        if sim is None:
            return
        first = None
        if timeout > 0 or not self._commands.empty():  # the check costs a fifth of a get that finds nothing
            try:
                first = self._commands.get(timeout=timeout) if timeout > 0 else self._commands.get_nowait()
            except queue.Empty:
                pass
        while first is not None:
            self._run(sim, first)
            try:
                first = self._commands.get_nowait()
            except queue.Empty:
                first = None
        now = time.perf_counter()
        if now >= self._next_snapshot:
            self._next_snapshot = now + 1.0 / self.rate
            self._snapshot()

    def _run(self, sim: Simulation, command: Command) -> None:
        """Run a person's command; what it answers, or what went wrong, becomes a note (never an exception)."""
        try:
            note = command(sim)
        except ApiError as e:
            note = str(e)
        except Exception as e:  # a bug in a command must not stop the simulation
            log.exception("viewer: a command failed")
            note = f"that did not work: {type(e).__name__}: {clip(str(e))}"
        if note:
            self._note(note)
        self._next_snapshot = 0.0  # show the effect at once

    def _note(self, text: str) -> None:
        stamp = self._sim.time if self._sim is not None and self._sim.loaded else 0.0
        self._notes.append(f"t = {stamp:.2f} s: {text}")
        del self._notes[:-5]

    def _world_changed(self, change: Any) -> None:
        if change.kind == "unloading":
            self._displays.clear()
            self._selected = None

    def _snapshot(self, force_layout: bool = False) -> None:
        sim = self._sim
        assert sim is not None
        wall = time.perf_counter()
        layout = None
        if not sim.loaded:
            self._layout, self._layout_key = layout_of(None), None
            layout = self._layout
        else:
            key = (id(sim.scene), sim.scene.version)
            if force_layout or key != self._layout_key or self._layout is None:
                self._layout, self._layout_key = layout_of(sim), key
                layout = self._layout
        assert self._layout is not None
        poses = np.empty((len(self._layout.frames), 7))
        if sim.loaded:
            backend = sim.backend
            for i, (entity, part) in enumerate(self._layout.parts):
                pos, quat = backend.get_pose(entity, part)
                poses[i, :3] = pos
                poses[i, 3:] = quat
        control = sim.control
        self._rtf_window.append((wall, sim.elapsed_time))
        while len(self._rtf_window) > 2 and wall - self._rtf_window[0][0] > 2.0:
            self._rtf_window.pop(0)
        (w0, t0), (w1, t1) = self._rtf_window[0], self._rtf_window[-1]
        rtf = (t1 - t0) / (w1 - w0) if w1 - w0 > 0.2 else float("nan")
        state = ("no world loaded" if not sim.loaded else "stopping" if control.stop else
                 "paused" if control.paused or (control.lockstep and control.pending_steps <= 0) else
                 f"running ({pace_name(control.realtime_factor)})")
        rtf_text = "–" if math.isnan(rtf) else f"{rtf:.2f}"
        status = (f"**{state}** · world `{sim.world.name}` · t = {sim.time:.2f} s · step {sim.step_count} · "
                  f"wall {wall - self._wall0:.1f} s · real-time factor {rtf_text}")
        d = self._displays
        texts = {
            "score": "  \n".join(d.values.values()) or "no score in this world",
            "events": "  \n".join(reversed(d.log[-15:])) or "no events yet",
            "result": "  \n".join(d.results.values()),
            "selection": self._describe(sim, self._selected),
            "notes": "  \n".join(reversed(self._notes)),
        }
        snap = Snapshot(sim.elapsed_steps, sim.time, wall, layout, poses, status, texts,
                        list(sim.agents) if sim.loaded else [],
                        list(sim.entity_names) if sim.loaded else [], pace=pace_name(control.realtime_factor))
        if sim.loaded:
            if self._overlays["scan"]:
                snap.scan = self._scan_points(poses)
            if self._overlays["contacts"]:
                snap.contacts = self._contact_points(sim)
            if d.grid is not None and d.grid_version != self._grid_sent:
                snap.grid = _grid_image(d.grid)
                self._grid_sent = d.grid_version
            for topic, value in d.images.items():
                if self._images_sent.get(topic) != d.image_versions[topic]:
                    self._images_sent[topic] = d.image_versions[topic]
                    image = _image(value)
                    if image is not None:
                        snap.images[topic] = image
        with self._wake:
            previous = self._mailbox
            if previous is not None and snap.layout is None and previous.layout is not None:
                snap.layout = previous.layout  # a layout the push thread has not seen yet is kept
            if previous is not None and snap.grid is None:
                snap.grid = previous.grid
            if previous is not None:  # images the push thread has not shown yet are kept (the newer win)
                for topic, image in previous.images.items():
                    snap.images.setdefault(topic, image)
            self._mailbox = snap
            self._wake.notify()

    def _describe(self, sim: Simulation, name: str | None) -> str:
        """The state of the selected entity (pose, velocity, tags, who grasps it, joint angles)."""
        if name is None:
            return "click an entity, or pick one above"
        if not sim.loaded or name not in sim.agents:
            return f"{quote(name)} is gone (deleted, or another world)"
        handle = sim.agents[name]
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
        info = sim.info.get(name) if name in sim.info.names else None
        if info is not None:
            lines.append(f"category: {info.category}; tags: {', '.join(info.tags) or 'none'}")
        held = sim.grasps.held_by(name)
        if held is not None:
            lines.append(f"grasped by: {held[0]} ({held[1]})")
        holding = [f"{obj} in {part}" for robot, part, obj in sim.grasps.items() if robot == name]
        if holding:
            lines.append(f"holding: {', '.join(holding)}")
        if isinstance(handle, RobotObj):
            angles = handle.all_joint_angles()
            if angles:
                lines.append("joints [rad]: " + ", ".join(f"{j} {a:.2f}" for j, a in angles.items()))
        return "  \n".join(lines)

    def _scan_points(self, poses: np.ndarray) -> np.ndarray:
        """The newest scan of every lidar as world points, from the pose of its frame in this snapshot."""
        layout = self._layout
        assert layout is not None
        out = [np.zeros((0, 3))]
        for scan in self._displays.scans.values():
            index = layout.index.get(str(scan.get("header", {}).get("frame_id", "")))
            if index is None:
                continue
            ranges = np.asarray(scan["ranges"], dtype=float)
            angles = scan["angle_min"] + scan["angle_increment"] * np.arange(len(ranges))
            ok = np.isfinite(ranges) & (ranges < scan["range_max"]) & (ranges >= scan["range_min"])
            local = np.stack([ranges[ok] * np.cos(angles[ok]), ranges[ok] * np.sin(angles[ok]),
                              np.zeros(int(ok.sum()))], axis=1)
            out.append(local @ quat_to_matrix(poses[index, 3:]).T + poses[index, :3])
        return np.vstack(out)

    def _contact_points(self, sim: Simulation) -> np.ndarray:
        """A marker at each part touching another entity (the floor contacts of wheels and casters left out)."""
        points = []
        for entity, part, other in sim.contact_triples():
            if other == "ground" and sim.agents[entity].kind == "robot" and part in sim.rolling_parts(entity):
                continue
            try:
                pos, _ = sim.backend.get_pose(entity, None if part == "main" else part)
            except Exception:  # a part the backend no longer has (deleted meanwhile): no marker
                continue
            points.append(pos)
        return np.array(points, dtype=float).reshape(-1, 3)

    # ------------------------------------------------------------------ the push thread
    def _push_loop(self) -> None:
        while True:
            with self._wake:
                while self._mailbox is None and not self._stopping:
                    self._wake.wait()
                if self._stopping:
                    return
                snap, self._mailbox = self._mailbox, None
            assert snap is not None
            try:
                self._push(snap)
            except Exception:  # a browser or viser failure must not stop the simulation: log and go on
                self.push_failures += 1
                if self.push_failures == 1 or self.push_failures % 100 == 0:
                    log.exception("viewer: sending an update failed (%d so far; the simulation goes on)",
                                  self.push_failures)
                time.sleep(0.1)

    def _push(self, snap: Snapshot) -> None:
        assert self._nodes is not None and self._panel is not None
        server = self._server
        if server is None:
            return
        with server.atomic():
            if snap.layout is not None:
                self._nodes.build(snap.layout, self._overlays)
            self._nodes.move(snap.poses, self._overlays["frames"])
            self._nodes.overlays(snap, self._overlays)
            self._panel.update(snap)
        self.pushed += 1
        for observer in list(self.push_observers):
            observer(snap)

    # ------------------------------------------------------------------ commands (queued by viser's threads)
    def _post(self, command: Command) -> None:
        self._commands.put(command)

    def _post_select(self, name: str) -> None:
        self._post(lambda sim: self.select(sim, name))

    def _post_move(self, name: str, position: np.ndarray, wxyz: np.ndarray) -> None:
        def run(sim: Simulation) -> str | None:
            note = move_entity(name, position, wxyz)(sim)
            if note is not None and self._panel is not None and name in sim.agents:
                self._panel.selected(name, self._drag_pose(sim, name))  # the handle goes back where it is
            return note
        self._post(run)

    def select(self, sim: Simulation, name: str) -> str | None:
        """Select entity ``name`` (its state is shown and the drag handle attached to it)."""
        if name not in sim.agents:
            return f"no entity {quote(name)} to select; entities: {', '.join(sim.entity_names) or 'none'}"
        self._selected = name
        if self._panel is not None:
            self._panel.selected(name, self._drag_pose(sim, name))
        return None

    def _drag_pose(self, sim: Simulation, name: str) -> tuple[np.ndarray, np.ndarray] | None:
        try:
            pos, quat = sim.backend.get_pose(name)
        except Exception:
            return None
        return np.asarray(pos, dtype=float), np.asarray(quat, dtype=float)

    def set_overlay(self, key: str, on: bool) -> None:
        """Turn an overlay on or off (``names``, ``frames``, ``scan``, ``contacts``, ``map``)."""
        self._overlays[key] = on
        self._next_snapshot = 0.0


# ------------------------------------------------------------------ the person's commands
def play(sim: Simulation) -> str | None:
    control = sim.control
    if not sim.loaded:
        return "no world is loaded: nothing to play"
    control.paused = False
    control.lockstep = False
    control.pending_steps = 0
    return None


def pause(sim: Simulation) -> str | None:
    sim.control.paused = True
    sim.control.pending_steps = 0
    return None


def step(n: Any) -> Command:
    def run(sim: Simulation) -> str | None:
        try:
            value = float(n)
        except (TypeError, ValueError):
            return f"steps must be a whole number from 1 to 100000, got {quote(str(n))}"
        if not value.is_integer() or not (1 <= value <= 100000):
            return f"steps must be a whole number from 1 to 100000, got {n}"
        count = int(value)
        if not sim.loaded:
            return "no world is loaded: nothing to step"
        sim.control.paused = True
        sim.control.pending_steps += count
        return None
    return run


def reset(sim: Simulation) -> str | None:
    if not sim.loaded:
        return "no world is loaded: nothing to reset"
    held = sim.grasps.items()
    sim.control.reset = True
    if held:
        released = "; ".join(f"{robot} let go of {obj}" for robot, _, obj in held)
        return f"reset to the start: {released}"
    return "reset to the start"


def set_pace(name: str) -> Command:
    def run(sim: Simulation) -> str | None:
        if name not in PACES:
            return f"unknown pace {quote(name)}; valid: {', '.join(PACES)}"
        sim.control.realtime_factor = PACES[name]
        return None
    return run


def send_message(agent: str, text: str) -> Command:
    def run(sim: Simulation) -> str | None:
        if not agent:
            return "pick an agent to send the message to"
        if not text.strip():
            return "type a message first"
        if agent not in sim.agents:
            return (f"agent {quote(agent)} no longer exists: the message was not sent; agents: "
                    f"{', '.join(sim.agents) or 'none'}")
        sim.send_msg(VIEWER_SENDER, agent, text)
        return f"sent to {agent}: {clip(text, 80)}"
    return run


def move_entity(name: str, position: np.ndarray, wxyz: np.ndarray) -> Command:
    """Teleport ``name`` through the API entries ``_setPosition`` and ``_setRotation`` (what a ROS client calls)."""
    def run(sim: Simulation) -> str | None:
        if name not in sim.agents:
            return f"{quote(name)} no longer exists: nothing was moved"
        model = next((e for e in sim.world.entities if e.name == name), None)
        if isinstance(model, Object) and model.static:
            return (f"{name} is static (fixed in place): it cannot be dragged; movable objects, robots and people "
                    "can")
        entries = {e.suffix: e for e in sim.api_entries()}
        p, q = [float(v) for v in position], [float(v) for v in wxyz]
        if not all(math.isfinite(x) for x in p + q) or not any(q):
            return (f"{name} was not moved: the position {p} [m] and the quaternion (w x y z) {q} must be finite "
                    "numbers, the quaternion non-zero")
        requests = [("_setPosition", {"name": name, "x": p[0], "y": p[1], "z": p[2]}),
                    ("_setRotation", {"name": name, "qw": q[0], "qx": q[1], "qy": q[2], "qz": q[3]})]
        if isinstance(model, Object) and sim.mode(name, "dynamics"):  # put down at rest, not thrown
            requests += [("_setVelocity", {"name": name}), ("_setAngularVelocity", {"name": name})]
        for suffix, request in requests:
            answer = call(sim, entries[suffix], name, request)
            if isinstance(answer, dict) and not answer.get("success", False):
                return f"{name} was not moved: {answer.get('message', '')}"
        return None
    return run


# ------------------------------------------------------------------ helpers
def _free(host: str, port: int) -> bool:
    """Whether ``port`` can be bound on ``host`` now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind((host if host not in ("", "localhost") else "127.0.0.1", port))
        except OSError:
            return False
    return True


def _grid_image(grid: dict[str, Any]) -> tuple[np.ndarray, float, float, np.ndarray, np.ndarray] | None:
    """An occupancy grid as a floor image: free white, occupied black, unknown grey."""
    info = grid.get("info", {})
    w, h, res = int(info.get("width", 0)), int(info.get("height", 0)), float(info.get("resolution", 0.0))
    data = np.asarray(grid.get("data", []), dtype=np.int16)
    if w <= 0 or h <= 0 or res <= 0 or data.size != w * h:
        return None
    cells = data.reshape(h, w)
    shade = np.where(cells < 0, 200, 255 - (np.clip(cells, 0, 100) * 255 // 100)).astype(np.uint8)
    image = np.repeat(np.flipud(shade)[:, :, None], 3, axis=2)  # row 0 of the grid is at the origin's y
    origin = info.get("origin", {})
    p, o = origin.get("position", {}), origin.get("orientation", {})
    quat = np.array([o.get("w", 1.0), o.get("x", 0.0), o.get("y", 0.0), o.get("z", 0.0)], dtype=float)
    centre = np.array([p.get("x", 0.0), p.get("y", 0.0), p.get("z", 0.0)]) + \
        quat_to_matrix(quat) @ np.array([w * res / 2, h * res / 2, 0.0])
    centre[2] += 0.003  # just above the floor
    return image, w * res, h * res, centre, quat


def _image(value: dict[str, Any]) -> np.ndarray | None:
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
