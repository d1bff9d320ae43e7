"""The one reader of a sigcore recording (``sigcore run --record``): what ``sigcore replay`` and the viewer's playback
(``sigcore view DIR``) both read.

:func:`open_recording` checks that a bag is a sigcore recording and reads its run's facts (the ``sigcore`` metadata
record: backend, timestep, seeds, the step the run started at, the controllers given on the command line, the names
of its own topics) and its attachments (the world file and its URDFs); :class:`RecordingFile` rebuilds the recorded
world from them (:meth:`RecordingFile.world`) and reads the messages. :class:`TruthReader` decodes the ground truth
(``/sigcore/ground_truth``, written in the recorder's own layout), :func:`decode_input` the input log
(``/sigcore/inputs``). The container (rosbag2 + MCAP) is :mod:`sigcore.record.bag_reading`'s.
"""

from __future__ import annotations

import json
import struct
import tempfile
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..sim.exceptions import ReplayError
from ..sim.inputs import Input
from ..world.randomize import sample
from .bag_reading import BagInfo, bag_info, iter_messages, read_extras
from .exceptions import BagError
from .recorder import GROUND_TRUTH, INPUTS
from .serialize import Serializer

if TYPE_CHECKING:
    from ..world import World

_ROS_TO_WXYZ = [0, 1, 2, 6, 3, 4, 5]
"""From a transform's (x, y, z, qx, qy, qz, qw) to a pose (x, y, z, qw, qx, qy, qz)."""


@dataclass
class RecordingFile:
    """A sigcore recording opened for reading (:func:`open_recording`).

    Attributes:
        path: The recording (its directory, or one ``.mcap`` file).
        info: What the container holds (topics, counts, times, problems of a cut file).
        facts: The run's facts (the ``sigcore`` metadata record).
        attachments: The recorded files (the world file, its URDFs, meshes): name -> bytes.
    """

    path: Path
    info: BagInfo
    facts: dict[str, str]
    attachments: dict[str, bytes]
    _serializer: Serializer | None = field(default=None, init=False, repr=False)

    @property
    def serializer(self) -> Serializer:
        """Decodes this recording's messages (made once, when first asked: building it takes a while)."""
        if self._serializer is None:
            self._serializer = Serializer()
        return self._serializer

    @property
    def truth_topic(self) -> str:
        """The topic of the ground truth (``/sigcore/ground_truth``)."""
        return self.facts.get("ground_truth", GROUND_TRUTH)

    @property
    def inputs_topic(self) -> str:
        """The topic of the input log (``/sigcore/inputs``)."""
        return self.facts.get("inputs", INPUTS)

    @property
    def backend(self) -> str:
        """The backend the run used."""
        return self.facts.get("backend", "mujoco")

    @property
    def dt_ns(self) -> int:
        """The run's timestep [ns]."""
        return round(float(self.facts.get("timestep", "0.002")) * 1e9)

    @property
    def start_step(self) -> int:
        """The step the run started at."""
        return int(self.facts.get("start_step", "0"))

    @property
    def controllers(self) -> dict[str, str]:
        """The controllers given on the command line instead of the world file's, by agent."""
        return dict(json.loads(self.facts.get("controllers") or "{}"))

    @property
    def seed(self) -> int | None:
        """The seed the run's world was drawn with (``sigcore run --seed``); None: as written."""
        return self._integer("seed")

    @property
    def noise_seed(self) -> int | None:
        """The seed of the run's sensor noise (``<world seed>``, or ``sigcore run --seed``); None: not recorded."""
        return self._integer("noise_seed")

    def _integer(self, fact: str) -> int | None:
        text = self.facts.get(fact, "")
        if text and not text.isdigit():
            raise ReplayError(f"{self.path}: the metadata's {fact} {text!r} is not an integer >= 0")
        return int(text) if text else None

    def has(self, topic: str) -> bool:
        """Whether the recording holds a message on ``topic``."""
        return any(t.name == topic and t.count > 0 for t in self.info.topics)

    def messages(self, topics: Iterable[str], written_order: bool = False) -> Iterator[tuple[str, int, bytes]]:
        """``(topic, log time [ns], CDR bytes)`` of the messages of ``topics``, in log-time order (``written_order``:
        in the order written, which is the order the commands of the input log were applied)."""
        return iter_messages(self.info, topics, written_order)

    def world(self, workdir: Path | None = None) -> World:
        """The recorded world: its original file when it is there with the recorded content, else the attached
        files written under ``workdir`` (a temporary folder by default); drawn with the recorded :attr:`seed` and
        with the recorded seed of its sensor noise, as the run had it.

        Raises:
            ReplayError: the world file is not attached (naming what the recording holds), or does not parse, or
                cannot be drawn with the recorded seed.
        """
        from ..world import WorldError

        try:
            world = self._parsed(workdir)
            if self.seed is not None:
                world = sample(world, self.seed)
        except WorldError as e:
            raise ReplayError(f"{self.path}: the recorded world does not load: {e}") from None
        noise = self.noise_seed
        if noise is not None and noise != world.seed:
            world = world.model_copy(update={"seed": noise})
        return world

    def _parsed(self, workdir: Path | None) -> World:
        """The recorded world file, parsed (see :meth:`world`)."""
        from ..world import parse_world

        name = self.facts.get("world_attachment", "")
        text = self.attachments.get(name)
        if text is None:
            raise ReplayError(f"{self.path}: the world file is not attached ({name or 'no sigcore metadata'}); "
                              f"attachments: {', '.join(self.attachments) or 'none'}")
        original = Path(self.facts.get("world_file", ""))
        if original.is_file() and original.read_bytes() == text:
            return parse_world(original)
        folder = Path(workdir or tempfile.mkdtemp(prefix="sigcore_replay_"))
        for rel, data in self.attachments.items():
            target = (folder / rel).resolve()
            if folder.resolve() not in target.parents:
                raise ReplayError(f"{self.path}: attachment {rel!r} would be written outside {folder}; a "
                                  "recording's files are named under world/, without '..'")
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        return parse_world(folder / name)


def open_recording(path: Path) -> RecordingFile:
    """Open the recording ``path`` (a bag directory or its ``.mcap`` file; one cut short is read as far as it goes,
    and its problems are in ``info.problems``).

    Raises:
        ReplayError: no bag there, or a bag that sigcore did not record (no ``sigcore`` metadata record): the message
            names the file and why.
    """
    try:
        info = bag_info(Path(path))
    except BagError as e:
        raise ReplayError(str(e)) from None
    metadata, attachments = read_extras(info)
    facts = metadata.get("sigcore", {})
    if not facts:
        files = ", ".join(str(f) for f in info.files) or str(info.path)
        raise ReplayError(f"{files} holds no 'sigcore' metadata record: it was not recorded by sigcore run --record")
    return RecordingFile(Path(path), info, facts, attachments)


def decode_input(serializer: Serializer, data: bytes) -> Input:
    """One message of the input log (``/sigcore/inputs``: a ``std_msgs/msg/String`` holding the JSON object).

    Raises:
        ValueError: the message does not decode or holds no input.
    """
    try:
        return Input.from_json(json.loads(serializer.deserialize("std_msgs/msg/String", data).data))
    except (KeyError, TypeError, AttributeError) as e:
        raise ValueError(f"not an input: {e}") from None


class TruthReader:
    """Reads ``/sigcore/ground_truth`` messages: ``(child frame names, (n, 7) poses x y z qw qx qy qz)``.

    The recorder writes every message of one scene with the same bytes but for the stamps and the numbers
    (``sigcore.record.recorder._TfLayout``): the first message of a layout is parsed field by field (CDR, XCDR1
    little endian), and each next one whose other bytes are the same is read at the offsets found then (a recording
    of an hour holds 100 000 of them; about 100 times faster than deserializing each). Anything else is decoded by
    the record's serializer. The numbers are read, not computed: a replay compares them bit for bit.

    Args:
        serializer: Decodes a message that is not in the recorder's layout (made when first needed if not given).
    """

    def __init__(self, serializer: Serializer | None = None) -> None:
        self._serializer = serializer
        self._template: np.ndarray | None = None
        self._fixed = np.zeros(0, dtype=np.intp)
        self._values = np.zeros(0, dtype=np.intp)
        self._children: tuple[str, ...] = ()

    def read(self, data: bytes) -> tuple[tuple[str, ...], np.ndarray]:
        """The frames one message names and their poses."""
        raw = np.frombuffer(data, dtype=np.uint8)
        template = self._template
        if template is not None and raw.size == template.size and np.array_equal(raw[self._fixed],
                                                                                 template[self._fixed]):
            values = raw[self._values].view("<f8").reshape(-1, 7)
            return self._children, values[:, _ROS_TO_WXYZ]
        try:
            children, poses, stamps, offsets = _parse_tf(data)
        except (ValueError, struct.error):
            return self._decode(data)
        byte8, byte56 = np.arange(8), np.arange(56)
        variable = np.concatenate([(np.asarray(stamps, dtype=np.intp)[:, None] + byte8).reshape(-1),
                                   (np.asarray(offsets, dtype=np.intp)[:, None] + byte56).reshape(-1)])
        fixed = np.ones(raw.size, dtype=bool)
        fixed[variable] = False
        self._template, self._fixed = raw.copy(), np.flatnonzero(fixed)
        self._values = (np.asarray(offsets, dtype=np.intp)[:, None] + byte56).reshape(-1)
        self._children = children
        return children, poses

    def poses(self, data: bytes) -> dict[str, np.ndarray]:
        """The message as ``child frame -> (x, y, z, qw, qx, qy, qz)``."""
        children, poses = self.read(data)
        return dict(zip(children, poses, strict=True))

    def _decode(self, data: bytes) -> tuple[tuple[str, ...], np.ndarray]:
        """Any ``TFMessage`` (big endian...), through rosbags' type store."""
        if self._serializer is None:
            self._serializer = Serializer()
        msg: Any = self._serializer.deserialize("tf2_msgs/msg/TFMessage", data)
        names = tuple(str(tf.child_frame_id) for tf in msg.transforms)
        poses = np.array([[tf.transform.translation.x, tf.transform.translation.y, tf.transform.translation.z,
                           tf.transform.rotation.w, tf.transform.rotation.x, tf.transform.rotation.y,
                           tf.transform.rotation.z] for tf in msg.transforms], dtype=float).reshape(-1, 7)
        self._template = None
        return names, poses


def _parse_tf(data: bytes) -> tuple[tuple[str, ...], np.ndarray, list[int], list[int]]:
    """A little-endian CDR ``tf2_msgs/msg/TFMessage``: child frames, poses, and the byte offsets of each
    transform's stamp and of its seven numbers.

    Raises:
        ValueError: not little-endian CDR, or it does not parse.
    """
    if len(data) < 8 or data[1] != 1:
        raise ValueError("not little-endian CDR")

    def align(pos: int, n: int) -> int:
        return pos + (-(pos - 4)) % n

    (count,) = struct.unpack_from("<I", data, 4)
    pos = 8
    children: list[str] = []
    stamps: list[int] = []
    offsets: list[int] = []
    rows: list[tuple[float, ...]] = []
    for _ in range(count):
        pos = align(pos, 4)
        stamps.append(pos)
        pos += 8
        for which in range(2):  # header.frame_id, child_frame_id
            pos = align(pos, 4)
            (size,) = struct.unpack_from("<I", data, pos)
            pos += 4
            if size < 1 or pos + size > len(data):
                raise ValueError("a string runs past the message")
            if which == 1:
                children.append(data[pos:pos + size - 1].decode())
            pos += size
        pos = align(pos, 8)
        offsets.append(pos)
        rows.append(struct.unpack_from("<7d", data, pos))
        pos += 56
    poses = np.array(rows, dtype=float).reshape(-1, 7)[:, _ROS_TO_WXYZ]
    return tuple(children), poses, stamps, offsets
