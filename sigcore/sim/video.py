"""Videos of a run (``sigcore run WORLD --video out.mp4``): a camera view rendered at the video's frame rate of
simulated time and encoded to MP4 (H.264) by FFmpeg through imageio-ffmpeg, with the time and the score in a corner.

The video keeps the simulated pace: a frame every ``round(1 / (fps * timestep))`` steps, and the file's frame rate is
``1 / (that many steps * timestep)``, so a run of 60 simulated seconds gives a video of 60 seconds whatever the
wall-clock time the run took. Frames are rendered like camera images (:mod:`sigcore.sim.camera`, off the simulation
thread with MuJoCo) and each shows exactly the step it is stamped with.

The view is a robot's ``<camera>`` (``--video-camera head`` or ``robot/head``) or ``overview``: a camera above the
room, south of it and looking north and down, placed so that every entity of the world at the start is in view.
The score is any publication a viewer shows as a ``value`` (the referee's score), through the publication contract.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backend import Backend, CameraView
from ..publish import Publication, PublicationSink
from ..world.models import Camera
from .camera import CameraFrame, CameraSensor
from .exceptions import VideoError

if TYPE_CHECKING:
    from .simulation import Simulation

log = logging.getLogger("sigcore")

OVERVIEW = "overview"
"""``--video-camera`` value of the camera that shows the whole room."""
OVERVIEW_SIZE = (640, 480)
"""Width and height [px] of the overview camera."""
ELEVATION = math.radians(55)
"""How far the overview camera looks down [rad]."""


class _Overview(CameraSensor):
    """A fixed camera that sees every entity: the view of ``--video-camera overview``."""

    def __init__(self, sim: Simulation, period_steps: int) -> None:
        w, h = OVERVIEW_SIZE
        model = Camera(name=OVERVIEW, link="", width=w, height=h, fov=math.radians(70), near=0.05, far=200.0,
                       rate=1.0 / (period_steps * sim.dt), type="rgb")
        super().__init__("", model, sim.dt, "world", 0)
        self.period_steps = period_steps
        names = list(sim.scene.entities)
        if names:
            boxes = [sim.scene.bounds(n) for n in names]
            low = np.min([b[0] for b in boxes], axis=0)
            high = np.max([b[1] for b in boxes], axis=0)
        else:
            low, high = np.array([-2.0, -2.0, 0.0]), np.array([2.0, 2.0, 1.0])
        centre = (low + high) / 2
        half = max(high[0] - low[0], (high[1] - low[1]) * w / h, 1.0) / 2
        distance = 1.05 * half / math.tan(model.fov / 2) + (high[2] - low[2]) / 2
        self._eye = centre + distance * np.array([0.0, -math.cos(ELEVATION), math.sin(ELEVATION)])
        forward = (centre - self._eye) / np.linalg.norm(centre - self._eye)
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        self._rotation = np.stack([right, np.cross(forward, right), forward], axis=1)

    def view(self, backend: Backend) -> CameraView:
        m = self.model
        return CameraView(self._eye, self._rotation, m.width, m.height, self.focal, self.cx, self.cy, m.near, m.far,
                          rgb=True, depth=False)


class _Scores(PublicationSink):
    """The latest text of every publication a viewer shows as a ``value`` (the score)."""

    def __init__(self) -> None:
        self.lines: dict[str, str] = {}
        self._shown: set[str] = set()

    def declare(self, publication: Publication) -> None:
        if publication.display == "value":
            self._shown.add(publication.topic)

    def wants(self, publication: Publication) -> bool:
        return publication.topic in self._shown

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        if publication.topic in self._shown:
            self.lines[publication.topic] = publication.display_text(value)


class VideoRecorder:
    """Writes a run's video; :meth:`close` finishes the file (the CLI does, however the run ends).

    Args:
        sim: The simulation (before its run).
        path: The MP4 file to write (its folder must exist).
        camera: ``overview``, a camera name of a robot (unique in the world), or ``robot/camera``.
        fps: Frames per second of simulated time wanted; the frame period is a whole number of steps.

    Raises:
        VideoError: the camera is unknown (names the valid ones), the folder does not exist, the frame rate is
            out of range, or the encoder is not installed.
    """

    def __init__(self, sim: Simulation, path: Path, camera: str = OVERVIEW, fps: float = 30.0) -> None:
        if not 0.1 <= fps <= 240:
            raise VideoError(f"--video-fps {fps:g} is out of range; valid: 0.1 <= fps <= 240")
        if path.suffix.lower() != ".mp4":
            raise VideoError(f"--video {path}: the file must end in .mp4")
        if not path.parent.is_dir():
            raise VideoError(f"--video {path}: no folder {path.parent}")
        try:
            import imageio_ffmpeg
        except ImportError:
            raise VideoError("--video needs imageio-ffmpeg (pip install imageio-ffmpeg; scripts/setup.sh installs "
                             "it)") from None
        self._sim = sim
        self.path = path
        self.period_steps = max(1, round(1.0 / (fps * sim.dt)))
        self.fps = 1.0 / (self.period_steps * sim.dt)
        """The file's frame rate: one frame per ``period_steps`` steps of simulated time."""
        if abs(self.fps - fps) > 1e-6 * fps:
            log.info("--video-fps %g is not a whole number of %g s steps: the video has %.4g frames per second "
                     "(one every %d steps), so that it keeps the simulated pace", fps, sim.dt, self.fps,
                     self.period_steps)
        self.sensor = self._sensor(camera)
        self.frames = 0
        """Frames written so far."""
        self.last_step = -1
        self._scores = _Scores()
        sim.publications.connect(self._scores)
        m = self.sensor.model
        self._size = (m.width + m.width % 2, m.height + m.height % 2)  # H.264 in yuv420p needs even sizes
        self._writer = imageio_ffmpeg.write_frames(str(path), self._size, fps=self.fps, codec="libx264",
                                                   pix_fmt_in="rgb24", pix_fmt_out="yuv420p", quality=None,
                                                   output_params=["-crf", "20", "-preset", "veryfast"],
                                                   macro_block_size=1, ffmpeg_log_level="error")
        self._writer.send(None)  # starts FFmpeg
        self._closed = False
        sim.cameras.watch(self.sensor, self._frame)

    def _sensor(self, camera: str) -> CameraSensor:
        sim = self._sim
        if camera == OVERVIEW:
            return _Overview(sim, self.period_steps)
        robot, _, name = camera.rpartition("/")
        matches = [s for s in sim.cameras.sensors if s.name == name and (not robot or s.robot == robot)]
        if len(matches) != 1:
            valid = [OVERVIEW] + [f"{s.robot}/{s.name}" for s in sim.cameras.sensors]
            why = "is ambiguous" if matches else "is not a camera of this world"
            raise VideoError(f"--video-camera {camera!r} {why}; valid: {', '.join(valid)}")
        found = matches[0]
        model = found.model.model_copy(update={"type": "rgb", "rate": 1.0 / (self.period_steps * sim.dt)})
        sensor = CameraSensor(found.robot, model, sim.dt, found.frame, 0)
        sensor.period_steps = self.period_steps
        return sensor

    def _frame(self, frame: CameraFrame) -> None:
        if self._closed or frame.rgb is None:
            return
        image = overlay(frame.rgb, frame.stamp_ns * 1e-9, list(self._scores.lines.values()))
        if image.shape[1] != self._size[0] or image.shape[0] != self._size[1]:
            padded = np.zeros((self._size[1], self._size[0], 3), dtype=np.uint8)
            padded[:image.shape[0], :image.shape[1]] = image
            image = padded
        self._writer.send(np.ascontiguousarray(image))
        self.frames += 1
        self.last_step = frame.step

    def close(self) -> None:
        """Deliver the frames in flight, then finish the file (idempotent)."""
        if self._closed:
            return
        self._sim.cameras.unwatch(self.sensor)
        self._closed = True
        self._sim.publications.disconnect(self._scores)
        try:
            self._writer.close()
        except Exception as e:  # FFmpeg failed (a full disk): what it wrote so far stays
            log.error("finishing the video %s failed: %s", self.path, e)

    @property
    def duration(self) -> float:
        """Length of the video written so far [s]."""
        return self.frames / self.fps


def overlay(rgb: np.ndarray, time: float, lines: list[str]) -> np.ndarray:
    """``rgb`` with the simulated time and ``lines`` (the score) on a dark band in the top-left corner."""
    from PIL import Image, ImageDraw

    image = Image.fromarray(rgb)
    draw = ImageDraw.Draw(image)
    text = "\n".join([f"t = {time:7.2f} s", *lines])
    left, top, right, bottom = draw.multiline_textbbox((6, 4), text)
    draw.rectangle((0, 0, right + 6, bottom + 4), fill=(0, 0, 0))
    draw.multiline_text((6, 4), text, fill=(255, 255, 255))
    return np.asarray(image)
