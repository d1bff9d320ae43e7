"""``sigcore run WORLD --record DIR``: every run as a rosbag2 (MCAP) recording, written from the simulation's own
messages on the simulation thread, with simulated log times. No message is lost and no ROS 2 install is needed.

What goes in (all of it, or the topics ``--record-topics`` regexes select):

- every declared publication (:mod:`sigcore.publish`): ``/tf_static``, ``robot_description``, ``/sigcore/scene``,
  the referee's score, events and result, the agents' ``_onRecvMsg`` / ``_onCollisionMsg`` / ``_scan``, SLAM's
  ``/map``, camera images while someone takes them;
- every topic a transport publishes of its own (ROS 2: ``/clock``, ``/tf``, odometry, joint states, scans,
  ``/sigcore/ready``), handed over already serialized (:meth:`sigcore.publish.PublicationSink.raw`);
- the ground truth, always: ``/sigcore/ground_truth`` (``tf2_msgs/msg/TFMessage``), the pose in ``world`` of every
  frame the scene has (``ground_truth/<entity>`` for objects and humans, ``ground_truth/<robot>/<link>`` for each
  link of a robot), at ``ground_truth_rate`` of simulated time (after a step's physics, before the commands applied
  before the next step), at the start and at the last step (when the recording closes: after the commands the run
  applied after its last step; a second message of that step when one was written before them);
- the input log, always: ``/sigcore/inputs`` (``std_msgs/msg/String``), one JSON object per command applied from
  outside (:mod:`sigcore.sim.inputs`), logged at the time of the step it took effect, which ``sigcore replay`` applies
  again;
- the world file and every URDF it uses as MCAP attachments, and the run's facts (sigcore's version, world, backend,
  timestep, the seed its ``<randomize>`` was drawn with and that of its sensor noise) as an MCAP metadata record
  ``sigcore``.

Camera images are costly to render: the recorder asks for them (:meth:`Recorder.wants`) only when a
``--record-topics`` pattern names their topic; otherwise it records them while another sink (a ROS 2 subscriber)
has them rendered.
"""

from __future__ import annotations

import json
import logging
import os
import re
import struct
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from .. import __version__
from ..publish import OFFERED, Offered, Publication, PublicationSink
from ..sim.inputs import Input
from ..world.urdf import resolve_mesh
from .bag import BagWriter
from .exceptions import BagError, RecordError, SerializeError
from .serialize import Serializer

if TYPE_CHECKING:
    from ..sim.simulation import Simulation

log = logging.getLogger("sigcore.record")

GROUND_TRUTH = "/sigcore/ground_truth"
"""The topic of the ground truth (``tf2_msgs/msg/TFMessage``)."""
GROUND_TRUTH_PREFIX = "ground_truth/"
"""The prefix of the ground truth's child frames."""
INPUTS = "/sigcore/inputs"
"""The topic of the input log (``std_msgs/msg/String``, one JSON object per command: step, kind, args)."""
GROUND_TRUTH_RATE = 30.0
"""Default rate of the ground truth [Hz of simulated time]."""
_TF = "tf2_msgs/msg/TFMessage"
_MESH_TYPES = {".stl": "model/stl", ".obj": "model/obj", ".dae": "model/vnd.collada+xml"}
_ROS_ORDER = [0, 1, 2, 4, 5, 6, 3]
"""From a backend's pose (x, y, z, qw, qx, qy, qz) to a transform's (x, y, z, qx, qy, qz, qw)."""


class Recorder(PublicationSink):
    """Records one simulation into a rosbag2 directory (see the module's docstring).

    Args:
        sim: The simulation (its world loaded; the recorder connects to its publications at once).
        path: The bag directory to create.
        topics: Regular expressions (``re.search``, like ``ros2 bag record -e``); a topic is recorded if one
            matches its full name. None or empty: every topic.
        ground_truth_rate: Rate of ``/sigcore/ground_truth`` [Hz of simulated time]; 0: only at the start and end.
        overwrite: Replace ``path`` if it holds a recording.

    Raises:
        RecordError: an invalid pattern or rate, or a directory that cannot be used (naming why).
    """

    takes_raw = True

    def __init__(self, sim: Simulation, path: Path, topics: list[str] | None = None,
                 ground_truth_rate: float = GROUND_TRUTH_RATE, overwrite: bool = False) -> None:
        self.sim = sim
        self._patterns: list[re.Pattern[str]] = []
        for text in topics or []:
            try:
                self._patterns.append(re.compile(text))
            except re.error as e:
                raise RecordError(f"--record-topics {text!r} is not a regular expression: {e}") from None
        if not ground_truth_rate >= 0 or ground_truth_rate == float("inf"):
            raise RecordError(f"ground truth rate {ground_truth_rate!r} is not a rate in Hz (>= 0; 0: start and end "
                              "only)")
        try:
            self.bag = BagWriter(Path(path), overwrite)
        except BagError as e:
            raise RecordError(str(e)) from None
        self.path = self.bag.path
        self._serializer = Serializer()
        self._selected: dict[str, bool] = {}
        self._topics: dict[str, Any] = {}  # full name -> the bag's topic (None: not recorded)
        self._unknown: set[str] = set()
        self._dt_ns = round(sim.dt * 1e9)
        self._every = max(1, round(1.0 / (ground_truth_rate * sim.dt))) if ground_truth_rate > 0 else 0
        self._last_truth = -1
        self._input_since_truth = False
        self._frames: tuple[tuple[str, str | None], ...] = ()  # a tuple: the backend keeps its indices
        self._tf: _TfLayout | None = None
        self._scene_version = -1
        self._scene: Any = None
        self.closed = False
        self._attach_world()
        self._subscriptions = (sim.events.subscribe("step", self._on_step),
                               sim.events.subscribe("input", self._on_input))
        sim.publications.connect(self)
        self._write_truth()

    # ------------------------------------------------------------------ selection
    def selected(self, topic: str) -> bool:
        """Whether ``topic`` (a full name) is recorded (the ground truth and the input log always are)."""
        hit = self._selected.get(topic)
        if hit is None:
            hit = self._selected[topic] = (not self._patterns or topic in (GROUND_TRUTH, INPUTS)
                                           or any(p.search(topic) for p in self._patterns))
        return hit

    def _topic(self, name: str, typename: str, offered: Offered, model: Any = None) -> Any:
        """The bag's topic ``name`` (registered on first use), or None when it is not recorded."""
        if name in self._topics:
            return self._topics[name]
        topic = None
        if self.selected(name):
            try:
                if model is not None:
                    self._serializer.register(typename, model)
                definition, digest = self._serializer.definition(typename)
                topic = self.bag.add_topic(name, typename, definition, digest, offered)
            except SerializeError as e:
                log.error("recording: %s is not recorded: %s", name, e)
        self._topics[name] = topic
        return topic

    # ------------------------------------------------------------------ PublicationSink
    def declare(self, publication: Publication) -> None:
        self._topic(publication.full_topic, publication.full_type, OFFERED[publication.qos], publication.model)

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        name = publication.full_topic
        topic = self._topics.get(name) if name in self._topics else self._topic(
            name, publication.full_type, OFFERED[publication.qos], publication.model)
        if topic is None or not self.bag.active:
            return
        try:
            data = self._serializer.serialize(publication.full_type, value)
        except SerializeError as e:
            if name not in self._unknown:
                self._unknown.add(name)
                log.error("recording: a value of %s cannot be serialized (logged once): %s", name, e)
            return
        self.bag.write(topic, stamp_ns, data)

    def raw(self, topic: str, msg_type: str, offered: Offered, stamp_ns: int, data: bytes) -> None:
        t = self._topics.get(topic) if topic in self._topics else self._topic(topic, msg_type, offered)
        if t is not None:
            self.bag.write(t, stamp_ns, data)

    def wants(self, publication: Publication) -> bool:
        """Costly values (camera images) are rendered for the recording only when a ``--record-topics`` pattern
        selects their topic."""
        return bool(self._patterns) and self.selected(publication.full_topic)

    # ------------------------------------------------------------------ the input log
    def _on_input(self, item: Input) -> None:
        """One command applied from outside: ``/sigcore/inputs``, logged at the time of its step."""
        topic = self._topic(INPUTS, "std_msgs/msg/String", OFFERED["events"])
        self._input_since_truth = True
        if topic is not None:
            text = json.dumps(item.to_json(), separators=(",", ":"))
            self.bag.write(topic, item.step * self._dt_ns, self._serializer.serialize("std_msgs/msg/String",
                                                                                       {"data": text}))

    # ------------------------------------------------------------------ ground truth
    def _on_step(self, sim: Simulation) -> None:
        if self._every and sim.step_count % self._every == 0:
            self._write_truth()

    def _write_truth(self, closing: bool = False) -> None:
        """``/sigcore/ground_truth`` now: every frame of the scene in ``world``, read with one ``get_poses``. Once per
        step; when ``closing``, again if commands were applied since this step's message (a replay compares each
        message where it was written)."""
        sim = self.sim
        if not self.bag.active or not sim.worlds.loaded:
            return
        step = sim.step_count
        if step == self._last_truth and not (closing and self._input_since_truth):
            return
        scene = sim.scene
        if scene.version != self._scene_version or scene is not self._scene or self._tf is None:
            # a spawn or delete changed the scene, or a world was loaded (a new scene, its version from 0 again)
            self._scene, self._scene_version = scene, scene.version
            frames, children = truth_frames(sim)
            self._frames = tuple(frames)
            self._tf = _TfLayout("world", children)
        topic = self._topic(GROUND_TRUTH, _TF, OFFERED["tf"])
        if topic is None:
            return
        poses = sim.backend.get_poses(self._frames) if self._frames else None
        self._last_truth = step
        self._input_since_truth = False
        self.bag.write(topic, sim.stamp_ns(), self._tf.pack(sim.stamp_ns(), poses))

    # ------------------------------------------------------------------ files
    def _attach_world(self) -> None:
        """The world file, its URDFs and their mesh files as attachments, the run's facts as metadata."""
        sim, bag = self.sim, self.bag
        world = sim.world
        files = world_files(world)
        source = Path(world.source).resolve()
        # each file under the folder that holds them all, at its place: the world file's relative paths
        # (``../models/x.urdf``) then name the same files when a replay writes them out elsewhere
        base = Path(os.path.commonpath([str(f.parent) for f in files])) if files else source.parent
        for file, media in files.items():
            bag.attach(f"world/{file.relative_to(base).as_posix()}", media, file.read_bytes())
        rel = source.relative_to(base).as_posix() if source in files else source.name
        bag.metadata("sigcore", {"version": __version__, "world": world.name, "world_file": str(source),
                                 "world_attachment": f"world/{rel}", "backend": sim.backend.name,
                                 "timestep": repr(sim.dt), "start_step": str(sim.step_count),
                                 "controllers": json.dumps(sim.worlds.first_controllers),
                                 "seed": "" if world.sample_seed is None else str(world.sample_seed),
                                 "noise_seed": str(world.seed),
                                 "ground_truth": GROUND_TRUTH, "inputs": INPUTS})

    # ------------------------------------------------------------------ the end
    def close(self) -> None:
        """The last step's ground truth (after the commands applied after it), then the bag closed
        (``metadata.yaml`` written). Idempotent."""
        if self.closed:
            return
        self.closed = True
        try:
            self._write_truth(closing=True)
        finally:
            self.sim.publications.disconnect(self)
            for subscription in self._subscriptions:
                subscription.cancel()
            self.bag.close({"sigcore_version": __version__, "world": self.sim.world.name})

    @property
    def messages(self) -> int:
        """Messages written so far."""
        return self.bag.messages


def world_files(world: Any) -> dict[Path, str]:
    """Every file a world is made of, resolved, with its media type: the world file, the URDFs its agents use, and
    the mesh files of its objects and of those URDFs (those that exist)."""
    files: dict[Path, str] = {}

    def add(path: Path | None, media: str) -> None:
        if path is not None and path.is_file():
            files.setdefault(path.resolve(), media)

    add(Path(world.source), "application/xml")
    for agent in world.agents:
        mesh = getattr(agent, "mesh", None)
        if mesh is not None:
            add(world.resolve(mesh), _MESH_TYPES.get(Path(mesh).suffix.lower(), "application/octet-stream"))
        if getattr(agent, "urdf", None) is None:
            continue
        doc = world.urdf(agent.name)
        add(doc.path, "application/xml")
        for element in doc.root.iter("mesh"):
            path = resolve_mesh(str(element.get("filename", "")), doc.path.parent)
            add(path, _MESH_TYPES.get(path.suffix.lower(), "application/octet-stream") if path else "")
    return files


def truth_frame(entity: str, frame: str, robot: bool) -> str:
    """The ground truth's child frame of ``frame`` of ``entity``: ``ground_truth/<robot>/<frame>`` for each frame of
    a robot or a person (``robot`` true; a person's feet, the frame named after it: ``ground_truth/<person>``),
    ``ground_truth/<entity>`` for an object's one frame."""
    return GROUND_TRUTH_PREFIX + (f"{entity}/{frame}" if robot and frame != entity else entity)


def truth_frames(sim: Simulation) -> tuple[list[tuple[str, str | None]], list[str]]:
    """Every frame of the scene as ``(entity, part)`` for ``Backend.get_poses``, and its ground-truth name."""
    parts: list[tuple[str, str | None]] = []
    names: list[str] = []
    for entity in sim.scene.entities:
        robot = entity in sim.entities and sim.entities[entity].kind in ("robot", "human")  # with link frames
        for frame, part in sim.scene.frame_parts(entity).items():
            parts.append((entity, part))
            names.append(truth_frame(entity, frame, robot))
    return parts, names


class _TfLayout:
    """A ``tf2_msgs/msg/TFMessage`` of fixed frames in CDR, in which only the stamp and the poses change: the byte
    offsets of each transform's stamp and its seven numbers are computed once (XCDR1, little endian)."""

    def __init__(self, parent: str, children: list[str]) -> None:
        buf = bytearray(b"\x00\x01\x00\x00")  # encapsulation: CDR, little endian
        self._stamps: list[int] = []
        self._values: list[int] = []

        def align(n: int) -> None:
            buf.extend(b"\x00" * (-(len(buf) - 4) % n))

        def string(text: str) -> None:
            align(4)
            data = text.encode() + b"\x00"
            buf.extend(struct.pack("<I", len(data)) + data)

        buf.extend(struct.pack("<I", len(children)))
        for child in children:
            align(4)
            self._stamps.append(len(buf))
            buf.extend(b"\x00" * 8)
            string(parent)
            string(child)
            align(8)
            self._values.append(len(buf))
            buf.extend(b"\x00" * 56)
        self._n = len(children)
        self._length = len(buf)
        self.length = self._length
        """The message's size [bytes]."""
        buf.extend(b"\x00" * (-(len(buf) - 4) % 8))  # whole float64 words after the header, for the views below
        self._buf = buf
        # every stamp is 4-aligned and every pose 8-aligned after the 4-byte header: numpy views write them at once
        self._u32 = np.frombuffer(buf, dtype="<u4", offset=4)
        self._f64 = np.frombuffer(buf, dtype="<f8", offset=4)
        self._sec = (np.array(self._stamps, dtype=np.int64) - 4) // 4
        self._nanosec = self._sec + 1
        self._words = (((np.array(self._values, dtype=np.int64) - 4) // 8)[:, None] + np.arange(7)).ravel()
        # from a row-major (n, 7) array of backend poses to the transforms' numbers, in one flat indexing
        self._source = (np.arange(len(children))[:, None] * 7 + np.array(_ROS_ORDER)).ravel()
        self.words = self._words
        """The indices, in the message's float64 words after its 4-byte header, of each transform's seven numbers
        (x, y, z, qx, qy, qz, qw), transform after transform."""

    def pack(self, stamp_ns: int, poses: Any) -> bytes:
        """The message stamped ``stamp_ns`` with ``poses`` ((n, 7): x, y, z, qw, qx, qy, qz per child)."""
        if self._n:
            sec, nanosec = divmod(stamp_ns, 1_000_000_000)
            self._u32[self._sec] = sec
            self._u32[self._nanosec] = nanosec
            self._f64[self._words] = np.asarray(poses, dtype="<f8").ravel()[self._source]
        return bytes(memoryview(self._buf)[:self._length])
