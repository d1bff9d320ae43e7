"""What ``sigcore replay`` checks while it re-simulates a recording: every recorded ground-truth frame at its step,
and the referee's score, events and result.

- :class:`TruthCheck` (a step observer) compares each ``/sigcore/ground_truth`` message with the replay's poses at the
  step it was recorded at: after that step's physics (and the observers of the features), before the commands noted
  at that step, as the recorder wrote it. The last frame of a whole run is compared at the very end, after the
  commands the run applied after its last step (a transport answers what is still queued when it stops), as the
  recorder wrote it when it closed. The first frame that is not equal (within the backend's tolerance) stops the
  replay: its step, time, entity and difference are kept in a :class:`Divergence`.
- :class:`TopicCheck` (a publication sink) collects what the replay publishes on the referee's topics
  (:data:`COMPARED_TOPICS`) and compares it, message by message and byte for byte (CDR), with what was recorded.

A frame costs one ``get_poses`` and one array comparison: 10,000 frames of 40 bodies take well under a second.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..publish import Publication, PublicationSink
from .exceptions import SerializeError
from .recorder import GROUND_TRUTH_PREFIX, truth_frames
from .serialize import Serializer

if TYPE_CHECKING:
    from ..sim.events import Subscription
    from ..sim.simulation import Simulation

__all__ = ["COMPARED_TOPICS", "Divergence", "ReplayCheck", "TopicCheck", "TopicVerdict", "TruthCheck",
           "frame_entity"]

SCORE, EVENTS, RESULT = "/referee/score", "/referee/events", "/referee/result"
COMPARED_TOPICS = (SCORE, EVENTS, RESULT)
"""The referee's publications (``plugins/referee``): a replay reproduces them message by message."""


def frame_entity(frame: str) -> str:
    """The entity a ground-truth frame belongs to (``ground_truth/robot_000/base_link`` -> ``robot_000``)."""
    return frame.removeprefix(GROUND_TRUTH_PREFIX).split("/", 1)[0]


@dataclass(frozen=True)
class Divergence:
    """The first recorded ground-truth frame the replay did not reproduce.

    Attributes:
        step: The step of the frame (the recording's step count).
        time: Its simulated time [s].
        index: Its index among the recorded messages (0: the first, at the start of the run).
        frame: The ground-truth child frame that differs most (``ground_truth/<entity>[/<link>]``).
        difference: The largest absolute difference of that frame's seven numbers [m, unit quaternion components];
            infinite when the frame is in one of the two only.
        recorded: Its recorded pose (x, y, z, qw, qx, qy, qz), or None when only the replay has it.
        replayed: Its pose in the replay, or None when only the recording has it.
        frames_differing: How many frames of that message are beyond the tolerance.
    """

    step: int
    time: float
    index: int
    frame: str
    difference: float
    recorded: tuple[float, ...] | None
    replayed: tuple[float, ...] | None
    frames_differing: int

    @property
    def entity(self) -> str:
        """The entity of :attr:`frame`."""
        return frame_entity(self.frame)

    def describe(self) -> str:
        """One line: where, which entity and by how much."""
        where = f"step {self.step} (t = {self.time:.3f} s, recorded message {self.index})"
        if self.recorded is None:
            return f"{where}: the replay has {self.frame} (entity '{self.entity}'), which the recording does not"
        if self.replayed is None:
            return f"{where}: the recording has {self.frame} (entity '{self.entity}'), which the replay does not"
        others = f"; {self.frames_differing - 1} other frame(s) differ too" if self.frames_differing > 1 else ""
        return (f"{where}: entity '{self.entity}' ({self.frame}) differs by {self.difference:.6g}: recorded "
                f"{_pose_text(self.recorded)}, replayed {_pose_text(self.replayed)}{others}")


def _pose_text(pose: tuple[float, ...]) -> str:
    return (f"xyz ({pose[0]:.9g}, {pose[1]:.9g}, {pose[2]:.9g}) wxyz ({pose[3]:.9g}, {pose[4]:.9g}, {pose[5]:.9g}, "
            f"{pose[6]:.9g})")


class TruthCheck:
    """Compares every recorded ground-truth message with the replay at its step (see the module's docstring).

    Args:
        frames: The recorded messages in the order written: ``(step, child frame -> x, y, z, qw, qx, qy, qz)``
            (:attr:`sigcore.record.replay.Recording.truth`); only those of the first world (up to where the step
            count goes back, a world load) are used.
        target: The step the replay runs to; frames after it are not compared.
        whole_run: The replay runs to the recording's end and applies the commands of the last step after it: the
            last frame is compared at :meth:`finish`, after them.
        tolerance: The largest difference taken as equal [m, unit quaternion components]; 0: bit for bit.
        dt: The timestep [s] (for the times in the report).
    """

    def __init__(self, frames: list[tuple[int, dict[str, np.ndarray]]], target: int, whole_run: bool,
                 tolerance: float, dt: float) -> None:
        kept: list[tuple[int, dict[str, np.ndarray]]] = []
        for step, poses in frames:
            if kept and step < kept[-1][0]:
                break  # a world was loaded: its steps count from 0 again (not replayed)
            if step <= target:
                kept.append((step, poses))
        self.frames = kept
        self.whole_run = whole_run and bool(kept) and kept[-1][0] == target
        self.tolerance = tolerance
        self.dt = dt
        self.compared = 0
        self._subscription: Subscription | None = None
        """Messages compared so far."""
        self.bitwise = 0
        """Of those, messages equal to the bit."""
        self.worst = 0.0
        """The largest difference seen within the tolerance [m, quaternion components]."""
        self.divergence: Divergence | None = None
        self._next = 0
        self._layout: tuple[Any, int, list[tuple[str, str | None]], list[str]] | None = None

    @property
    def total(self) -> int:
        """Messages to compare."""
        return len(self.frames)

    @property
    def first_step(self) -> int | None:
        return self.frames[0][0] if self.frames else None

    @property
    def last_step(self) -> int | None:
        return self.frames[-1][0] if self.frames else None

    def attach(self, sim: Simulation) -> None:
        """Compare the frames of the start (before the first step and its commands) and observe every step."""
        self._compare_due(sim)
        if self.divergence is None:
            self._subscription = sim.events.subscribe("step", self._on_step)

    def finish(self, sim: Simulation) -> None:
        """The replay has ended: compare the last frame of a whole run (after the commands of the last step)."""
        if self._subscription is not None:
            self._subscription.cancel()
        if self.divergence is None and self.whole_run and self._next == len(self.frames) - 1 \
                and self.frames[-1][0] == sim.step_count:
            self._compare(sim, self._next)
            self._next += 1

    def _on_step(self, sim: Simulation) -> None:
        frames = self.frames
        if self._next < len(frames) and frames[self._next][0] <= sim.step_count:
            self._compare_due(sim)

    def _compare_due(self, sim: Simulation) -> None:
        """Compare the frames recorded at this step (not the last of a whole run: :meth:`finish` does)."""
        frames, step = self.frames, sim.step_count
        end = len(frames) - 1 if self.whole_run else len(frames)
        while self._next < end and frames[self._next][0] <= step and self.divergence is None:
            if frames[self._next][0] == step:
                self._compare(sim, self._next)
            self._next += 1  # a frame of a step the replay skipped cannot happen: stepping is one by one

    def _compare(self, sim: Simulation, index: int) -> None:
        step, recorded = self.frames[index]
        names, now = self._poses(sim)
        self.compared += 1
        if list(recorded) != names:  # a frame in one of the two only, or listed in another order
            only = next((n for n in [*recorded, *names] if (n in recorded) != (n in names)), None)
            if only is not None:
                theirs, mine = recorded.get(only), dict(zip(names, now, strict=True)).get(only)
                self._diverged(sim, step, index, only, float("inf"),
                               None if theirs is None else tuple(theirs.tolist()),
                               None if mine is None else tuple(mine.tolist()), 1)
                return
            recorded = {n: recorded[n] for n in names}
        reference = np.array(list(recorded.values())).reshape(len(names), 7)
        if np.array_equal(reference, now):
            self.bitwise += 1
            return
        diff = np.max(np.abs(reference - now), axis=1)
        diff = np.where(np.isnan(diff), np.inf, diff)
        worst = int(np.argmax(diff))
        if diff[worst] <= self.tolerance:
            self.worst = max(self.worst, float(diff[worst]))
            return
        self._diverged(sim, step, index, names[worst], float(diff[worst]), tuple(reference[worst].tolist()),
                       tuple(now[worst].tolist()), int(np.count_nonzero(diff > self.tolerance)))

    def _diverged(self, sim: Simulation, step: int, index: int, frame: str, difference: float,
                  recorded: tuple[float, ...] | None, replayed: tuple[float, ...] | None, count: int) -> None:
        self.divergence = Divergence(step, step * self.dt, index, frame, difference, recorded, replayed, count)
        sim.control.stop("the replay diverged from the recorded ground truth")

    def _poses(self, sim: Simulation) -> tuple[list[str], np.ndarray]:
        """The names and poses ((n, 7): x, y, z, qw, qx, qy, qz) of every scene frame now, in the recorder's
        order; the frames are listed again only when the scene changed (a spawn, a delete)."""
        scene = sim.scene
        layout = self._layout
        if layout is None or layout[0] is not scene or layout[1] != scene.version:
            parts, names = truth_frames(sim)
            layout = self._layout = (scene, scene.version, parts, names)
        parts, names = layout[2], layout[3]
        poses = np.asarray(sim.backend.get_poses(parts), dtype=float) if parts else np.empty((0, 7))
        return names, poses.reshape(len(names), 7)

    def summary(self) -> list[str]:
        """The report's lines: how many recorded messages were compared and how; then how the last one compared
        (``ground truth at step S: N frames, ...``, N the bodies' and links' frames it holds)."""
        if not self.frames:
            return ["ground truth: no message recorded up to this step: not compared"]
        span = f"steps {self.first_step} to {self.last_step}"
        if self.divergence is not None:
            return [f"ground truth: DIVERGED at {self.divergence.describe()}; the {self.divergence.index} recorded "
                    "messages before it were reproduced"]
        if self.compared < self.total:
            return [f"ground truth: {self.compared} of {self.total} recorded messages compared ({span}): the replay "
                    "ended before the others"]
        if self.bitwise == self.compared:
            first = f"ground truth: all {self.total} recorded messages ({span}) bitwise equal, each at its step"
            verdict = "bitwise equal"
        else:
            first = (f"ground truth: all {self.total} recorded messages ({span}) within the tolerance "
                     f"{self.tolerance:g}, each at its step ({self.bitwise} bitwise equal; largest difference "
                     f"{self.worst:.3g})")
            verdict = f"within the tolerance {self.tolerance:g}"
        step, last = self.frames[-1]
        return [first, f"ground truth at step {step}: {len(last)} frames, {verdict}"]

    @property
    def ok(self) -> bool:
        """Every frame to compare was compared, and reproduced."""
        return self.divergence is None and self.compared == self.total


@dataclass
class TopicVerdict:
    """How one compared topic was reproduced.

    Attributes:
        topic: The topic.
        recorded: Its messages in the recording, up to the replay's end [(log time [ns], CDR bytes)].
        replayed: Those the replay published.
        mismatch: The index of the first message that differs (or is missing on one side), None if all are equal.
    """

    topic: str
    recorded: list[tuple[int, bytes]]
    replayed: list[tuple[int, bytes]]
    mismatch: int | None = None


class TopicCheck(PublicationSink):
    """Collects what the replay publishes on the compared topics and compares it with the recording (see the
    module's docstring).

    Args:
        recorded: Every recorded message of each compared topic that the recording holds: topic -> [(log time [ns],
            CDR bytes)] in the order written. A topic absent here was not recorded: it is not compared.
    """

    def __init__(self, recorded: dict[str, list[tuple[int, bytes]]]) -> None:
        self.recorded = recorded
        self.replayed: dict[str, list[tuple[int, bytes]]] = {}
        self.serializer = Serializer()
        self.types: dict[str, str] = {}
        self.errors: list[str] = []

    def declare(self, publication: Publication) -> None:
        topic = publication.full_topic
        if topic in self.recorded:
            if publication.model is not None:
                self.serializer.register(publication.full_type, publication.model)
            self.types[topic] = publication.full_type
            self.replayed.setdefault(topic, [])

    def publish(self, publication: Publication, stamp_ns: int, value: dict[str, Any]) -> None:
        topic = publication.full_topic
        if topic not in self.recorded:
            return
        try:
            self.replayed.setdefault(topic, []).append((stamp_ns, self.serializer.serialize(publication.full_type,
                                                                                          value)))
        except SerializeError as e:
            self.errors.append(f"{topic}: {e}")

    def wants(self, publication: Publication) -> bool:
        """Only the compared topics: nothing costly (a camera image, a scan) is made for this sink."""
        return publication.full_topic in self.recorded

    def verdicts(self, end_ns: int) -> list[TopicVerdict]:
        """Each compared topic's messages up to ``end_ns`` (the replay's last step), recorded and replayed."""
        out = []
        for topic in COMPARED_TOPICS:
            if topic not in self.recorded:
                continue
            recorded = [m for m in self.recorded[topic] if m[0] <= end_ns]
            replayed = [m for m in self.replayed.get(topic, []) if m[0] <= end_ns]
            mismatch = next((i for i, (a, b) in enumerate(zip(recorded, replayed, strict=False)) if a != b), None)
            if mismatch is None and len(recorded) != len(replayed):
                mismatch = min(len(recorded), len(replayed))
            out.append(TopicVerdict(topic, recorded, replayed, mismatch))
        return out

    def decode(self, topic: str, data: bytes) -> Any:
        """A message of a compared topic as a rosbags dataclass (None when its type is unknown here)."""
        typename = self.types.get(topic)
        if typename is None:
            return None
        try:
            return self.serializer.deserialize(typename, data)
        except Exception:  # a recorded message of another definition: shown as bytes only
            return None

    def lines(self, end_ns: int) -> tuple[list[str], bool]:
        """The report's lines about the referee and whether everything compared was reproduced."""
        verdicts = self.verdicts(end_ns)
        if not verdicts:
            return ["referee: no score, events or result recorded (no referee, or --record-topics left them out): "
                    "not compared"], True
        lines: list[str] = []
        ok = not self.errors
        for v in verdicts:
            ok = ok and v.mismatch is None
            lines.append(self._line(v))
        lines += [f"referee: a replayed message could not be serialized: {e}" for e in self.errors]
        return lines, ok

    def _line(self, v: TopicVerdict) -> str:
        what = {SCORE: "score", EVENTS: "events", RESULT: "result"}[v.topic]
        if v.mismatch is None:
            if v.topic == SCORE:
                last = self.decode(v.topic, v.recorded[-1][1]) if v.recorded else None
                value = f" {last.data}" if last is not None else ""
                return f"referee: score{value} reproduced ({len(v.recorded)} messages on {v.topic}, byte for byte)"
            if v.topic == RESULT:
                if not v.recorded:
                    return f"referee: result: none published up to here, none in the replay ({v.topic})"
                msg = self.decode(v.topic, v.recorded[-1][1])
                value = f" '{msg.result}', score {msg.score}" if msg is not None else ""
                return f"referee: result{value} reproduced ({v.topic}, byte for byte)"
            return f"referee: all {len(v.recorded)} events reproduced ({v.topic}, byte for byte, with their times)"
        i = v.mismatch
        rec = v.recorded[i] if i < len(v.recorded) else None
        rep = v.replayed[i] if i < len(v.replayed) else None
        return (f"referee: {what} NOT reproduced ({v.topic}: {len(v.recorded)} recorded, {len(v.replayed)} "
                f"replayed): message {i + 1} differs: recorded {self._text(v.topic, rec)}, replayed "
                f"{self._text(v.topic, rep)}")

    def _text(self, topic: str, message: tuple[int, bytes] | None) -> str:
        if message is None:
            return "none"
        stamp, data = message
        msg = self.decode(topic, data)
        at = f"at t = {stamp / 1e9:.3f} s"
        if msg is None:
            return f"{len(data)} bytes {at}"
        if topic == SCORE:
            return f"{msg.data} {at}"
        if topic == EVENTS:
            return f"{msg.kind} {msg.points:+d} '{msg.text}' (score {msg.score}) {at}"
        return f"'{msg.result}' score {msg.score} {at}"


class ReplayCheck:
    """Everything a replay checks: the ground truth (:class:`TruthCheck`) and the referee's topics
    (:class:`TopicCheck`).

    Args:
        truth: The recorded ground-truth frames (see :class:`TruthCheck`).
        topics: The recorded messages of the compared topics (see :class:`TopicCheck`).
        target: The step the replay runs to.
        whole_run: It runs to the recording's end (see :class:`TruthCheck`).
        tolerance: See :class:`TruthCheck` [m, unit quaternion components].
        dt: The timestep [s].
    """

    def __init__(self, truth: list[tuple[int, dict[str, np.ndarray]]], topics: dict[str, list[tuple[int, bytes]]],
                 target: int, whole_run: bool, tolerance: float, dt: float) -> None:
        self.truth = TruthCheck(truth, target, whole_run, tolerance, dt)
        self.topics = TopicCheck(topics)

    def attach(self, sim: Simulation) -> None:
        """Before the replay runs: listen to its publications, compare the first frame, observe the steps."""
        sim.publications.connect(self.topics)
        self.truth.attach(sim)

    def finish(self, sim: Simulation) -> None:
        """After the replay has run (its transport stopped): compare the last frame, stop listening."""
        self.truth.finish(sim)
        sim.publications.disconnect(self.topics)

    def report(self, sim: Simulation) -> tuple[list[str], bool]:
        """The report's lines and whether everything compared was reproduced (the referee's topics are compared
        up to the step the replay reached)."""
        lines, ok = self.topics.lines(sim.stamp_ns())
        return [*self.truth.summary(), *lines], ok and self.truth.ok
