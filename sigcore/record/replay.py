"""``sigcore replay DIR``: re-simulate a recorded run from its world and its input log, with no client attached, and
check it against the recorded ground truth.

The recording holds the world file (an attachment; the original file is used when it is still there, unchanged),
the backend, the controllers given on the command line, the step the run started at and ended at, and every command
applied from outside with the step it took effect (``/sigcore/inputs``, :mod:`sigcore.sim.inputs`). A
:class:`Replayer` is the run's only transport: serviced between steps like the ROS 2 transport was, it applies the
commands of each step through the same core paths (an API call, a drive's velocity, a reset, a spawn, a delete, an
entity's information), and polls deferred answers after each step as the ROS 2 transport did. The commands noted at
the run's last step arrived after it (a transport answers what is still queued when it stops): the replayer applies
them when it stops there, as the run did. MuJoCo is deterministic: every recorded ground-truth frame, and the
referee's score, events and result, are reproduced bit for bit (:mod:`sigcore.record.verify` compares them).
``--until STEP`` stops at a step and hands the simulation, paused, to live clients.
"""

from __future__ import annotations

import json
import logging
import tempfile
from dataclasses import dataclass, field
from itertools import takewhile
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..sim.inputs import Input, ReplayError
from ..transport import Transport
from ..world.randomize import sample
from .bag import BagError, BagInfo, bag_info, read_extras
from .recorder import GROUND_TRUTH, INPUTS, _TfLayout, truth_frames
from .serialize import Serializer
from .verify import COMPARED_TOPICS

if TYPE_CHECKING:
    from ..api.deferred import Deferred
    from ..api.table import ApiEntry
    from ..sim.events import Subscription
    from ..sim.simulation import Simulation
    from ..world import World

log = logging.getLogger("sigcore.record")

__all__ = ["Recording", "ReplayError", "Replayer", "compare", "decode_input", "describe_inputs", "load_recording",
           "poses_now"]


@dataclass
class Recording:
    """What a replay needs from a recording (:func:`load_recording`)."""

    path: Path
    info: BagInfo
    facts: dict[str, str]
    attachments: dict[str, bytes]
    inputs: list[Input]
    truth: list[tuple[int, dict[str, np.ndarray]]] = field(default_factory=list)
    """Every ground-truth message in the order written: (step, child frame -> x, y, z, qw, qx, qy, qz)."""
    topics: dict[str, list[tuple[int, bytes]]] = field(default_factory=dict)
    """The recorded messages of the compared topics (the referee's, :data:`~sigcore.record.verify.COMPARED_TOPICS`)
    that the recording holds: topic -> [(log time [ns], CDR bytes)] in the order written."""

    @property
    def start_step(self) -> int:
        return int(self.facts.get("start_step", "0"))

    @property
    def final_step(self) -> int:
        """The run's last step (that of the last ground truth, written when the run ended)."""
        return self.truth[-1][0] if self.truth else self.start_step

    @property
    def controllers(self) -> dict[str, str]:
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


def load_recording(path: Path) -> Recording:
    """Read what a replay needs from the recording ``path``.

    Raises:
        ReplayError: the recording is cut, foreign, or was not made by ``sigcore run --record`` (naming why).
    """
    from mcap.reader import make_reader

    try:
        info = bag_info(path)
    except BagError as e:
        raise ReplayError(str(e)) from None
    if info.problems:
        raise ReplayError(f"{path} cannot be replayed: {info.problems[0]}")
    serializer = Serializer()
    metadata, attachments = read_extras(info)
    facts = metadata.get("sigcore", {})
    if not facts:
        raise ReplayError(f"{path} was not recorded by sigcore run --record (no 'sigcore' metadata record): it "
                          "cannot be replayed")
    dt_ns = round(float(facts["timestep"]) * 1e9)
    inputs: list[Input] = []
    truth: list[tuple[int, dict[str, np.ndarray]]] = []
    decode_truth = TruthDecoder(serializer)
    compared = {t.name for t in info.topics} & set(COMPARED_TOPICS)
    topics: dict[str, list[tuple[int, bytes]]] = {t: [] for t in compared}
    for file in info.files:
        with open(file, "rb") as f:
            # in the order written (the order the commands were applied), not sorted by log time
            for _, channel, message in make_reader(f).iter_messages(topics=[INPUTS, GROUND_TRUTH, *compared],
                                                                    log_time_order=False):
                if channel.topic == INPUTS:
                    inputs.append(decode_input(serializer, message.data))
                elif channel.topic == GROUND_TRUTH:
                    truth.append((message.log_time // dt_ns, decode_truth(message.data, message.log_time)))
                else:
                    topics[channel.topic].append((message.log_time, bytes(message.data)))
    return Recording(Path(path), info, facts, attachments, inputs, truth, topics)


class TruthDecoder:
    """Decodes ``/sigcore/ground_truth`` messages into ``child frame -> (x, y, z, qw, qx, qy, qz)``.

    A message of the same frames as the one before has its numbers at the same byte offsets: they are read at once
    and the message is checked by writing it again with the recorder's layout (bytes equal: the frames, their
    order, the stamp and the numbers are what was read); any other message is deserialized in full (a run's first
    message, and the first after a spawn or a delete). About 100 times faster than deserializing every message.

    Args:
        serializer: Deserializes the messages that do not fit the layout of the one before.
    """

    _BACKEND_ORDER = [0, 1, 2, 6, 3, 4, 5]
    """From a transform's (x, y, z, qx, qy, qz, qw) to a backend's pose (x, y, z, qw, qx, qy, qz)."""

    def __init__(self, serializer: Serializer) -> None:
        self._serializer = serializer
        self._layout: _TfLayout | None = None
        self._children: list[str] = []

    def __call__(self, data: bytes, stamp_ns: int) -> dict[str, np.ndarray]:
        """The poses one message holds (``stamp_ns``: its log time, which the recorder stamps it with)."""
        layout = self._layout
        if layout is not None and len(data) == layout.length and (len(data) - 4) % 8 == 0:
            numbers = np.frombuffer(data, dtype="<f8", offset=4)
            poses = numbers[layout.words].reshape(-1, 7)[:, self._BACKEND_ORDER]
            if layout.pack(stamp_ns, poses) == data:
                return dict(zip(self._children, poses, strict=True))
        msg = self._serializer.deserialize("tf2_msgs/msg/TFMessage", data)
        poses = np.array([[tf.transform.translation.x, tf.transform.translation.y, tf.transform.translation.z,
                           tf.transform.rotation.w, tf.transform.rotation.x, tf.transform.rotation.y,
                           tf.transform.rotation.z] for tf in msg.transforms], dtype=float).reshape(-1, 7)
        self._children = [tf.child_frame_id for tf in msg.transforms]
        parents = {tf.header.frame_id for tf in msg.transforms}
        self._layout = _TfLayout(parents.pop(), self._children) if len(parents) == 1 else None
        return dict(zip(self._children, poses, strict=True))


def decode_input(serializer: Serializer, data: bytes) -> Input:
    """One message of the input log (``/sigcore/inputs``: a ``std_msgs/msg/String`` holding the JSON object).

    Raises:
        ValueError: the message does not decode or holds no input (``json``, ``KeyError`` as ``ValueError``).
    """
    try:
        return Input.from_json(json.loads(serializer.deserialize("std_msgs/msg/String", data).data))
    except (KeyError, TypeError, AttributeError) as e:
        raise ValueError(f"not an input: {e}") from None


class Replayer(Transport):
    """The transport of a replay: applies the recorded commands between steps (see the module's docstring).

    Args:
        inputs: The recorded commands, in the order they were applied.
        until: Apply the commands up to the first noted at this step or later (None: all); the log's order is
            kept (a world loaded during the run restarts the step count: what follows it is not applied then).
        end: The step the recorded run ended at: when the replay stops there, the commands noted at it (which
            the run applied after its last step, while its transport stopped) are applied then, as they were.
            None: not applied (a replay that stops before the end).
    """

    name = "replay"

    def __init__(self, inputs: list[Input], until: int | None = None, end: int | None = None) -> None:
        self._inputs = list(takewhile(lambda i: until is None or i.step < until, inputs))
        self._end = end
        self._next = 0
        self._subscription: Subscription | None = None
        self._held: list[tuple[ApiEntry, str, Deferred]] = []
        self._sim: Simulation | None = None
        self.applied = 0
        self.after_end = 0
        """Of :attr:`applied`, the commands applied after the last step (noted at the run's last step: the run
        applied them while it stopped, after its last step)."""
        self.error: str | None = None
        """Why the replay stopped early: a command that cannot be applied again (:class:`ReplayError`); the run
        then ends before the next step (``stop_reason`` ``"replay error"``)."""

    def start(self, sim: Simulation) -> None:
        self._sim = sim
        self._subscription = sim.events.subscribe("step", self._poll_held)

    def service(self, timeout: float) -> None:
        sim = self._sim
        assert sim is not None
        inputs = self._inputs
        while self.error is None and self._next < len(inputs) and inputs[self._next].step <= sim.step_count:
            item = inputs[self._next]
            self._next += 1
            try:
                if item.step < sim.step_count:
                    raise ReplayError(f"the command of step {item.step} ({item.kind}) comes after step "
                                      f"{sim.step_count}: the recording's input log is out of order")
                result = self._apply(sim, item)
            except ReplayError as e:  # the run ends before the next step, saying why (not a traceback)
                self.error = str(e)
                sim.control.pause()
                sim.control.stop("replay error")
                return
            if result is not None:
                self._held.append(result)
            self.applied += 1

    def stop(self) -> None:
        sim = self._sim
        if sim is None:
            return
        if self._subscription is not None:
            self._subscription.cancel()
        if self._end is not None and sim.step_count == self._end and self.error is None:
            before = self.applied
            self.service(0.0)  # the commands the run applied after its last step, as its transport stopped
            self.after_end = self.applied - before

    @property
    def pending(self) -> int:
        """Commands not applied yet."""
        return len(self._inputs) - self._next

    def _apply(self, sim: Simulation, item: Input) -> tuple[ApiEntry, str, Deferred] | None:
        """Apply one command; an API call whose answer is deferred is returned, to be polled after each step."""
        return sim.inputs.apply(item)

    def _poll_held(self, sim: Simulation) -> None:
        """Poll deferred answers after each step, as the transport that took the calls did."""
        if not self._held:
            return
        from ..api.call import finish

        self._held = [(entry, agent, d) for entry, agent, d in self._held if finish(sim, entry, agent, d) is None]


def poses_now(sim: Simulation) -> dict[str, np.ndarray]:
    """Every scene frame's pose now, named as in the ground truth (``ground_truth/<entity>`` or
    ``ground_truth/<robot>/<link>``)."""
    parts, names = truth_frames(sim)
    poses = sim.backend.get_poses(parts) if parts else np.empty((0, 7))
    return dict(zip(names, poses, strict=True))


def compare(recorded: dict[str, np.ndarray], now: dict[str, np.ndarray]) -> tuple[bool, float, str]:
    """``(bitwise equal, largest difference, the frame where it is)`` of two sets of poses; a frame in one set only
    counts as an infinite difference."""
    worst, where = 0.0, ""
    for name in sorted(set(recorded) | set(now)):
        if name not in recorded or name not in now:
            return False, float("inf"), name
        diff = float(np.max(np.abs(recorded[name] - now[name])))
        if diff > worst or (diff != diff):
            worst, where = diff, name
    equal = all(np.array_equal(recorded[n], now[n]) for n in recorded)
    return equal, worst, where


def describe_inputs(inputs: list[Input]) -> dict[str, int]:
    """How many commands of each kind a recording holds."""
    out: dict[str, int] = {}
    for item in inputs:
        out[item.kind] = out.get(item.kind, 0) + 1
    return out
