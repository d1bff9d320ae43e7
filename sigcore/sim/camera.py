"""Cameras: pinhole RGB and depth images of a robot's view, rendered off the simulation thread.

Each :class:`CameraSensor` is a ``<camera>`` of a robot. At every step where a camera is due, the simulation takes the
backend renderer's snapshot of that step (:meth:`sigcore.backend.Renderer.snapshot`, a copy of the state) and the
camera's view (its optical frame in the world, from the link's pose). A renderer that is ``threaded`` (MuJoCo) draws
the snapshot on the render thread while physics goes on; the finished :class:`CameraFrame` is published on the
simulation thread at a later step (or when the simulation goes idle), stamped with the step it shows. A renderer that
is not threaded (PyBullet's TinyRenderer holds the interpreter) draws at once.

At most two frames are in flight: one rendering, one waiting with its snapshot. When the renderer falls behind the
camera's rate, the simulation waits for it rather than dropping images: every camera delivers one image per period
of simulated time, whatever the machine's speed.

Topics (through the publication contract, so every transport, the viewer and a recorder get them), for a camera
``cam`` of robot ``r`` (under the robot's namespace when spawned with one):

* ``/r/cam/image_raw`` (``sensor_msgs/Image``, rgb8) and ``/r/cam/camera_info`` when it renders colour;
* ``/r/cam/depth/image_raw`` (32FC1, metres along the optical axis, +inf where nothing is within ``far``) and
  ``/r/cam/depth/camera_info`` when it renders depth.

All are in the camera's optical frame (``<camera>_optical_frame``, in the TF tree: :mod:`sigcore.sim.frames`).
"""

from __future__ import annotations

import logging
import math
import queue
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..agent.exceptions import ApiError
from ..backend import Array, Backend, CameraView, Image, Renderer
from ..errors import BackendError
from ..geometry import quat_from_rpy, quat_mul, quat_rotate, quat_to_matrix
from ..isolation import USER_ERRORS, describe
from ..publish import Publication, Publications, Publisher
from ..text import quote
from ..world.models import Camera
from .frames import OPTICAL

if TYPE_CHECKING:
    from .simulation import Simulation

log = logging.getLogger("sigcore")

_STOP = object()


@dataclass(frozen=True)
class CameraFrame:
    """One image of a camera.

    Attributes:
        robot: The robot carrying the camera.
        camera: The camera's name.
        frame: The TF frame of the image (the camera's optical frame, prefixed like the robot's frames).
        step: The simulation step the image shows (the state right after that step).
        stamp_ns: The simulated time of that step [ns].
        rgb: (height, width, 3) uint8, row 0 at the top; None for a depth-only camera.
        depth: (height, width) float32 [m] along the optical axis; None for an rgb-only camera.
        info: The ``sensor_msgs/CameraInfo`` fields (without header).
    """

    robot: str
    camera: str
    frame: str
    step: int
    stamp_ns: int
    rgb: Image | None
    depth: Image | None
    info: dict[str, Any] = field(repr=False)


class CameraSensor:
    """A ``<camera>`` of a robot: its intrinsics, its period in steps and its view at a step.

    Args:
        robot: The robot's name.
        model: The ``<camera>`` element.
        timestep: The simulation's timestep [s].
        frame: The TF name of its optical frame.
        seed: Seed of its depth noise.
    """

    def __init__(self, robot: str, model: Camera, timestep: float, frame: str, seed: int) -> None:
        self.robot = robot
        self.model = model
        self.frame = frame
        self.period_steps = max(1, round(1.0 / (model.rate * timestep)))
        f, cx, cy = model.intrinsics
        self.focal, self.cx, self.cy = f, cx, cy
        self._offset = np.asarray(model.pose.xyz, dtype=float)
        self._rotation = quat_mul(np.asarray(quat_from_rpy(*model.pose.rpy)), np.asarray(OPTICAL))
        self.rng = np.random.default_rng(seed)
        self.info = {"height": model.height, "width": model.width, "distortion_model": "plumb_bob",
                     "d": [0.0] * 5, "k": [f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0],
                     "r": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
                     "p": [f, 0.0, cx, 0.0, 0.0, f, cy, 0.0, 0.0, 0.0, 1.0, 0.0]}
        """The ``sensor_msgs/CameraInfo`` fields without header: no distortion, K = P's left 3x3."""

    @property
    def name(self) -> str:
        return self.model.name

    def pose(self, backend: Backend) -> tuple[Array, Array]:
        """The optical frame's position [m] and orientation (w, x, y, z) in the world, now."""
        pos, quat = backend.get_pose(self.robot, self.model.link)
        return pos + quat_rotate(quat, self._offset), quat_mul(quat, self._rotation)

    def view(self, backend: Backend) -> CameraView:
        """What to render of this camera now."""
        pos, quat = self.pose(backend)
        m = self.model
        return CameraView(pos, quat_to_matrix(quat), m.width, m.height, self.focal, self.cx, self.cy, m.near,
                          m.far, rgb=m.type != "depth", depth=m.type != "rgb")


@dataclass
class _Job:
    sensors: list[CameraSensor]
    views: list[CameraView]
    snapshot: object
    step: int
    stamp_ns: int
    frames: list[CameraFrame] | None = None
    error: str | None = None


class Cameras:
    """Every camera of a simulation, its render thread and its publications (the one owner of camera state).

    Args:
        sim: The simulation (its backend, publications, frames and step clock are read).
    """

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        self.sensors: list[CameraSensor] = []
        self._publishers: dict[tuple[str, str], list[tuple[str, Publisher]]] = {}
        self._watched: dict[int, tuple[CameraSensor, Callable[[CameraFrame], None]]] = {}  # id(view) -> (view, taker)
        self._renderer: Renderer | None = None
        self._failed: str | None = None
        self._jobs: queue.Queue[Any] = queue.Queue(maxsize=1)
        self._done: queue.Queue[_Job] = queue.Queue()
        self.in_flight = 0
        """Frames handed to the render thread and not yet published (the simulation polls while there are)."""
        self.every = 0
        """The greatest common divisor of the cameras' periods [steps]: a camera can be due only at a multiple of it
        (0: no camera). The simulation calls :meth:`capture` at those steps and while frames are in flight."""
        self._thread: threading.Thread | None = None
        self._seed = sim.world.seed + 7919

    def _changed(self) -> None:
        """Recompute :attr:`every` after cameras or watched views came or went."""
        views = (*self.sensors, *(sensor for sensor, _ in self._watched.values()))
        self.every = math.gcd(*(s.period_steps for s in views))

    # ------------------------------------------------------------------ cameras come and go
    def add(self, robot: str, cameras: Sequence[Camera], namespace: str = "") -> None:
        """Add the cameras of ``robot`` and declare their topics."""
        sim = self._sim
        for camera in cameras:
            sensor = CameraSensor(robot, camera, sim.dt, sim.frames.name(robot, camera.optical_frame),
                                  self._seed + len(self.sensors))
            self.sensors.append(sensor)
            self._publishers[(robot, camera.name)] = self._declare(sim.publications, sensor, namespace)
        self._changed()

    def remove(self, robots: Sequence[str]) -> None:
        """Forget the cameras of ``robots`` (deleted while running) and withdraw their topics; frames of theirs
        still rendering are dropped."""
        gone = set(robots)
        self.settle()
        for key in [k for k in self._publishers if k[0] in gone]:
            for topic, _ in self._publishers.pop(key):
                self._sim.publications.withdraw(topic)
        self.sensors = [s for s in self.sensors if s.robot not in gone]
        self._changed()

    @staticmethod
    def _declare(publications: Publications, sensor: CameraSensor,
                 namespace: str) -> list[tuple[str, Publisher]]:
        base = f"{namespace}/{sensor.robot}/{sensor.name}"
        what = f"<camera name='{sensor.name}'> of robot '{sensor.robot}'"
        kinds = (["rgb"] if sensor.model.type != "depth" else []) + (["depth"] if sensor.model.type != "rgb" else [])
        out = []
        for kind in kinds:
            prefix = base if kind == "rgb" else f"{base}/depth"
            image = Publication(f"{prefix}/image_raw", "sensor_msgs/msg/Image", "sensor",
                                f"{'colour (rgb8)' if kind == 'rgb' else 'depth (32FC1, m)'} images of {what}")
            info = Publication(f"{prefix}/camera_info", "sensor_msgs/msg/CameraInfo", "sensor",
                               f"the intrinsics of the {kind} images of {what}")
            out += [(kind, publications.declare(image)), (f"{kind}_info", publications.declare(info))]
        return [(p.publication.topic, p) for _, p in out]

    def watch(self, sensor: CameraSensor, on_frame: Callable[[CameraFrame], None]) -> None:
        """Render ``sensor`` at its rate for ``on_frame`` alone (called on the simulation thread, in step order), not
        published and whether or not anything receives publications (a video, :mod:`sigcore.sim.video`)."""
        self._watched[id(sensor)] = (sensor, on_frame)
        self._changed()

    def unwatch(self, sensor: CameraSensor) -> None:
        """Stop rendering ``sensor`` for its watcher (frames in flight are delivered first)."""
        self.settle()
        self._watched.pop(id(sensor), None)
        self._changed()

    # ------------------------------------------------------------------ on request (the API's services)
    def find(self, robot: str, camera: str = "") -> CameraSensor:
        """The camera ``camera`` of ``robot`` (empty: its first).

        Raises:
            ApiError: the robot has no such camera (names those it has).
        """
        mine = [s for s in self.sensors if s.robot == robot]
        if not mine:
            raise ApiError(f"robot {quote(robot)} has no <camera>; add one in the world file "
                           "(<camera name=... link=...> inside its <robot>)")
        if not camera:
            return mine[0]
        for sensor in mine:
            if sensor.name == camera:
                return sensor
        raise ApiError(f"robot {quote(robot)} has no camera {quote(camera)}; its cameras: "
                       f"{', '.join(s.name for s in mine)}")

    def grab(self, sensor: CameraSensor) -> CameraFrame:
        """An image of ``sensor`` now (the current step), not published; frames in flight are published first.

        Raises:
            ApiError: the cameras are off (the renderer failed: the message says why).
        """
        self.settle()
        sim = self._sim
        if self._failed is None:
            try:
                renderer = self._renderer or self._make_renderer()
                job = _Job([sensor], [sensor.view(sim.backend)], renderer.snapshot(), sim.step_count, sim.stamp_ns())
            except BackendError as e:
                self._fail(str(e))
            else:
                if renderer.threaded:
                    self._start_thread()
                    self._jobs.put(job)
                    job = self._done.get(timeout=60.0)
                else:
                    self._render(renderer, job)
                if job.error is not None:
                    self._fail(job.error)
                elif job.frames:
                    return job.frames[0]
        raise ApiError(f"cameras are off: {self._failed}")

    def distance(self, sensor: CameraSensor) -> float:
        """Distance [m] from ``sensor``'s optical centre along its optical axis to the nearest surface of another
        entity or the ground, within its ``far`` distance (``inf`` beyond), by a ray cast (no rendering)."""
        pos, quat = sensor.pose(self._sim.backend)
        axis = quat_to_matrix(quat)[:, 2]
        hit = self._sim.backend.ray_cast(pos, axis[None, :], sensor.model.far, exclude=sensor.robot)
        return float(hit[0])

    # ------------------------------------------------------------------ each step
    def capture(self, step: int) -> None:
        """Take the views of the cameras due at ``step`` (the simulation calls this after each step), and publish
        the frames that finished rendering. A camera is rendered only while something takes its images (a
        ``camera`` subscriber on ``sim.events``, or a sink that wants one of its topics: a ROS 2 subscriber)."""
        due = [s for s in self.sensors if step % s.period_steps == 0 and self._wanted(s)]
        due += [s for s, _ in self._watched.values() if step % s.period_steps == 0]
        if due and self._failed is None:
            self._submit(due, step)
        if self.in_flight:
            self.poll()

    def _wanted(self, sensor: CameraSensor) -> bool:
        """Whether anyone takes this camera's images now: a ``camera`` subscriber, or a sink that wants one of its
        topics (ROS 2: a subscriber)."""
        if self._sim.events.wanted("camera"):
            return True
        return any(p.wanted for _, p in self._publishers.get((sensor.robot, sensor.name), ()))

    def _submit(self, due: list[CameraSensor], step: int) -> None:
        sim = self._sim
        try:
            renderer = self._renderer or self._make_renderer()
            job = _Job(due, [s.view(sim.backend) for s in due], renderer.snapshot(), step, sim.stamp_ns())
        except BackendError as e:
            self._fail(str(e))
            return
        if not renderer.threaded:
            self._render(renderer, job)
            self._publish(job)
            return
        self._start_thread()
        while True:  # the render thread has one job waiting at most: wait for it, publishing what finishes
            try:
                self._jobs.put(job, timeout=0.05)
                break
            except queue.Full:
                self.poll()
                if self._failed is not None:
                    return
        self.in_flight += 1

    def _start_thread(self) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._worker, name="sigcore-render", daemon=True)
            self._thread.start()

    def _make_renderer(self) -> Renderer:
        self._renderer = self._sim.backend.renderer()
        return self._renderer

    def poll(self, wait: bool = False) -> None:
        """Publish the frames that finished rendering (all of those in flight when ``wait``)."""
        while self.in_flight:
            try:
                job = self._done.get(timeout=60.0) if wait else self._done.get_nowait()
            except queue.Empty:
                if wait:
                    self._fail("the render thread gave no image within 60 s")
                return
            self.in_flight -= 1
            if job.error is not None:
                self._fail(job.error)
            else:
                self._publish(job)

    def settle(self) -> None:
        """Wait for every frame in flight and publish it (when the simulation goes idle, stops or is reset)."""
        if self.in_flight:
            self.poll(wait=True)

    def close(self) -> None:
        """Publish what is in flight, stop the render thread and free the renderer."""
        self.settle()
        if self._thread is not None:
            self._jobs.put(_STOP)
            self._thread.join(timeout=30.0)
            self._thread = None
        elif self._renderer is not None:
            self._renderer.close()
        self._renderer = None

    # ------------------------------------------------------------------ rendering
    def _worker(self) -> None:
        renderer = self._renderer
        assert renderer is not None
        while True:
            job = self._jobs.get()
            if job is _STOP:
                break
            self._render(renderer, job)
            self._done.put(job)
        try:
            renderer.close()
        except USER_ERRORS:
            log.exception("closing the camera renderer failed")

    def _render(self, renderer: Renderer, job: _Job) -> None:
        try:
            images = renderer.render(job.snapshot, job.views)
        except USER_ERRORS as e:  # a renderer that fails (no OpenGL, a driver error) disables cameras, not the run
            job.error = describe(e)
            return
        job.frames = []
        for sensor, (rgb, depth) in zip(job.sensors, images, strict=True):
            if depth is not None and sensor.model.noise > 0:
                hit = np.isfinite(depth)
                noisy = np.array(depth, dtype=np.float32)
                noisy[hit] += sensor.rng.normal(0.0, sensor.model.noise, int(hit.sum())).astype(np.float32)
                depth = noisy
            job.frames.append(CameraFrame(sensor.robot, sensor.name, sensor.frame, job.step, job.stamp_ns, rgb,
                                          depth, sensor.info))

    def _fail(self, error: str) -> None:
        if self._failed is None:
            self._failed = error
            log.error("cameras are off for the rest of this world: %s (the simulation goes on without images)",
                      error)

    @property
    def failure(self) -> str | None:
        """Why the cameras stopped (the renderer failed), or None."""
        return self._failed

    # ------------------------------------------------------------------ publishing
    def _publish(self, job: _Job) -> None:
        for sensor, frame in zip(job.sensors, job.frames or (), strict=True):
            watched = self._watched.get(id(sensor))
            if watched is not None:
                watcher = watched[1]
                try:
                    watcher(frame)
                except USER_ERRORS:
                    log.exception("the watcher of camera view '%s' raised (the simulation goes on)", sensor.name)
                continue
            key = (frame.robot, frame.camera)
            publishers = self._publishers.get(key)
            if publishers is None:  # its robot was deleted meanwhile
                continue
            header = {"stamp": frame.stamp_ns, "frame_id": frame.frame}
            info = {"header": header, **frame.info}
            for topic, publisher in publishers:
                if not publisher.active:
                    continue
                if topic.endswith("camera_info"):
                    publisher.publish(info, frame.stamp_ns)
                elif topic.endswith("/depth/image_raw"):
                    publisher.publish(image_fields(header, frame.depth, "32FC1"), frame.stamp_ns)
                else:
                    publisher.publish(image_fields(header, frame.rgb, "rgb8"), frame.stamp_ns)
            try:  # a feature's subscriber that raises disables the feature (the hub); another one's is logged
                self._sim.events.emit("camera", frame)
            except USER_ERRORS:
                log.exception("a camera subscriber raised (the simulation goes on)")


def image_fields(header: dict[str, Any], image: Image | None, encoding: str) -> dict[str, Any]:
    """The ``sensor_msgs/Image`` fields of ``image`` (rgb8: (h, w, 3) uint8; 32FC1: (h, w) float32)."""
    assert image is not None
    height, width = image.shape[:2]
    return {"header": header, "height": height, "width": width, "encoding": encoding, "is_bigendian": 0,
            "step": width * (3 if encoding == "rgb8" else 4), "data": np.ascontiguousarray(image).view(np.uint8)}
