"""The recorded data a playback shows (``sigcore view DIR``), read once by :func:`load` through the one reader of
recordings (:mod:`sigcore.record.reader`). A recording made by ``sigcore run --record`` (:mod:`sigcore.record`) holds
everything the viewer needs:

* the **world** (the world file and its URDFs as attachments): the scene layout is built from it exactly as for a
  live run (a :class:`~sigcore.sim.Simulation` of it is constructed, never stepped, only for ``sim.scene``, the
  declared publications and each entity's pose in the world file), with the entities the run spawned (the input
  log's spawns applied to it);
* the **ground truth** (``/sigcore/ground_truth``, ``tf2_msgs/TFMessage`` at 30 Hz of simulated time and at the last
  step): the pose of every frame, ``ground_truth/<entity>`` for objects and humans, ``ground_truth/<robot>/<frame>``
  for each frame of a robot. At a moment ``t`` every frame is where the newest ground truth at or before ``t`` has
  it; a frame no ground truth names stays where the world file puts it, and one the ground truth named before but
  not at ``t`` (its entity was deleted) is hidden;
* the **publications** a viewer shows as text (a publication's ``display``: the referee's score, events and result),
  decoded from the bag and turned into the same lines the live viewer shows (:meth:`Publication.display_text`); a
  reset or another world in the input log (``/sigcore/inputs``) clears the events and the result, as it does live;
* laser scans and occupancy grids (kept serialized, decoded when shown) for the overlays.
"""

from __future__ import annotations

import bisect
import dataclasses
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from sigcore.errors import SigcoreError, ViewerError

from ..exceptions import Interrupted
from ..scenebuild import SceneLayout, layout_of

if TYPE_CHECKING:
    from sigcore.publish import Publication
    from sigcore.record.reader import RecordingFile

log = logging.getLogger("sigcore.viewer")

LOG_SHOWN = 15
"""Events shown (newest first), as live."""

_SCAN = "sensor_msgs/msg/LaserScan"
_GRID = "nav_msgs/msg/OccupancyGrid"


@dataclass
class Lines:
    """The lines of the publications a viewer shows as text, with the log time and order they were recorded in.

    Attributes:
        values: ``display="value"`` publications: topic -> ``[(time [ns], order, line)]``.
        log: ``display="log"`` lines of every such publication: ``[(time [ns], order, line)]``, in order.
        results: ``display="result"``: topic -> ``[(time [ns], order, line)]``.
        resets: ``(time [ns], order)`` of each reset of the run (the events and the result start over).
        worlds: ``(time [ns], order)`` of each world loaded while running (every text starts over).
    """

    values: dict[str, list[tuple[int, int, str]]] = field(default_factory=dict)
    log: list[tuple[int, int, str]] = field(default_factory=list)
    results: dict[str, list[tuple[int, int, str]]] = field(default_factory=dict)
    resets: list[tuple[int, int]] = field(default_factory=list)
    worlds: list[tuple[int, int]] = field(default_factory=list)

    def at(self, t_ns: int) -> dict[str, str]:
        """The score, events and result texts the live viewer showed at ``t_ns`` (as it builds them)."""
        cleared = _last_before(self.worlds, t_ns)
        restarted = max(cleared, _last_before(self.resets, t_ns))
        shown: list[tuple[int, str]] = []
        for lines in self.values.values():
            seen = [item for item in lines[:_count_until(lines, t_ns)] if item[1] > cleared]
            if seen:
                shown.append((seen[0][1], seen[-1][2]))  # in the order they first appeared, the newest line
        events: list[str] = []
        for _, order, line in reversed(self.log[:_count_until(self.log, t_ns)]):
            if order <= restarted or len(events) == LOG_SHOWN:
                break
            events.append(line)
        results = []
        for lines in self.results.values():
            seen = [item for item in lines[:_count_until(lines, t_ns)] if item[1] > restarted]
            if seen:
                results.append((seen[0][1], seen[-1][2]))
        return {
            "score": "  \n".join(line for _, line in sorted(shown)) or "no score in this world",
            "events": "  \n".join(events) or "no events yet",
            "result": "  \n".join(line for _, line in sorted(results)),
        }


def _count_until(items: list[tuple[int, int, str]], t_ns: int) -> int:
    """How many of ``items`` (sorted by time) are logged at or before ``t_ns``."""
    return bisect.bisect_right(items, (t_ns, math.inf, ""))


def _last_before(marks: list[tuple[int, int]], t_ns: int) -> int:
    """The order of the newest mark at or before ``t_ns`` (-1: none)."""
    k = bisect.bisect_right(marks, (t_ns, math.inf))
    return marks[k - 1][1] if k else -1


@dataclass
class Serialized:
    """Messages of one topic kept as recorded (decoded when shown): log times [ns] and CDR bytes."""

    typename: str
    times: list[int] = field(default_factory=list)
    data: list[bytes] = field(default_factory=list)

    def index_at(self, t_ns: int) -> int:
        """The newest message at or before ``t_ns`` (-1: none yet)."""
        return bisect.bisect_right(self.times, t_ns) - 1


@dataclass
class Recorded:
    """Everything a recording shows (:func:`load`).

    Attributes:
        path: The recording.
        world: The recorded world's name; backend: the backend it ran on; dt_ns: its timestep [ns].
        layout: The scene's frames and visuals, built as for a live run.
        kinds: Each entity's kind (robot, object, human).
        base: (frames, 7) every frame's pose in the world file.
        tracked: (frames,) whether the ground truth names the frame at all.
        times: (n,) log time of each ground-truth message [ns], ascending.
        poses: (n, frames, 7) each frame's pose in each message (that of ``base`` where it names none).
        present: (n, frames) whether each message names the frame.
        lines: The texts' lines.
        scans: Laser scans by topic; grids: occupancy grids by topic.
        start_ns, end_ns: The recording's first and last log time [ns].
        problems: What is wrong with the recording (cut...), from :func:`sigcore.record.bag_info`.
        untracked: Frames the ground truth names that the scene has not (entities spawned while running whose spawn
            could not be rebuilt).
    """

    path: Path
    world: str
    backend: str
    dt_ns: int
    layout: SceneLayout
    kinds: dict[str, str]
    base: np.ndarray
    tracked: np.ndarray
    times: np.ndarray
    poses: np.ndarray
    present: np.ndarray
    lines: Lines
    scans: dict[str, Serialized]
    grids: dict[str, Serialized]
    start_ns: int
    end_ns: int
    problems: list[str]
    untracked: list[str]

    def index_at(self, t_ns: int) -> int:
        """The newest ground-truth message at or before ``t_ns`` (-1: before the first)."""
        return int(np.searchsorted(self.times, t_ns, side="right")) - 1

    def poses_at(self, t_ns: int) -> tuple[np.ndarray, np.ndarray]:
        """``(poses (frames, 7), hidden (frames,))`` at ``t_ns``: the newest ground truth at or before it; frames it
        does not name where the world file puts them, hidden when an earlier or later message names them (their
        entity was not there then)."""
        i = self.index_at(t_ns)
        if i < 0:
            return self.base.copy(), np.zeros(len(self.base), dtype=bool)
        return self.poses[i].copy(), self.tracked & ~self.present[i]


def load(path: Path, workdir: Path, stop: Callable[[], bool] | None = None) -> Recorded:
    """Read the recording ``path`` (a bag directory or its ``.mcap`` file; a cut one as far as it goes).

    Args:
        path: The recording.
        workdir: Where the attached world files are written when the original world file is gone or changed.
        stop: Asked every few thousand messages: true ends the reading with :class:`Interrupted`.

    Raises:
        Interrupted: ``stop()`` became true.
        ViewerError: the recording's world cannot be rebuilt (not recorded by sigcore, the world file or a URDF not
            attached, the world does not load) or it holds no ground truth; the message names the file and what is
            missing.
    """
    from sigcore.record.reader import open_recording
    from sigcore.sim.exceptions import ReplayError

    path = Path(path)
    try:
        recording = open_recording(path)
    except ReplayError as e:
        raise ViewerError(str(e)) from None
    if not recording.has(recording.truth_topic):
        raise ViewerError(f"{_files(recording.info)} holds no ground truth (no message on {recording.truth_topic}): "
                          "there is nothing to show the scene with")
    try:
        world = recording.world(workdir)
    except SigcoreError as e:
        raise ViewerError(f"the recorded world cannot be rebuilt: {e}") from None
    sim = _scene_of(world, recording.backend, path)
    try:
        _spawn_recorded(sim, recording)
        layout = layout_of(sim)
        base = sim.backend.get_poses(layout.parts) if layout.parts else np.empty((0, 7))
        kinds = {name: sim.entities[name].kind for name in sim.entities.names if name in sim.entities}
        robots = {name for name, kind in kinds.items() if kind in ("robot", "human")}  # entities with link frames
        shown = [p for p in sim.publications.declared if p.display is not None]
        overlays = [p for p in sim.publications.declared if p.msg_type in (_SCAN, _GRID)]
        dt_ns = round(sim.dt * 1e9)
    finally:
        sim.cameras.close()
    names = [_truth_name(entity, part, frame, robots) for (entity, part), frame in zip(layout.parts, layout.frames,
                                                                                       strict=True)]
    return _read(recording, layout, kinds, np.asarray(base, dtype=float), names, shown, overlays, dt_ns,
                 world.name, stop or (lambda: False))


def _spawn_recorded(sim: Any, recording: RecordingFile) -> None:
    """Add to the scene every entity the run spawned (the input log's spawns, in their order), so that they are
    drawn: the ground truth shows them from their spawn on and hides them before. A spawn that cannot be rebuilt
    (a file it named is gone, a recording made before spawns were logged with their requests) is skipped: its frames
    are listed as not drawn."""
    from sigcore.record.reader import decode_input
    from sigcore.sim.inputs import spawn_request_of

    if not recording.has(recording.inputs_topic):
        return
    path = recording.path
    for _, t_ns, data in recording.messages([recording.inputs_topic]):
        try:
            item = decode_input(recording.serializer, data)
            if item.kind != "spawn" or "requests" not in item.args:
                continue
            requests = [spawn_request_of(r) for r in item.args["requests"]]
            for outcome in sim.entities.spawn(requests):
                if not isinstance(outcome, str):
                    log.warning("viewer: %s: an entity spawned at %.3f s is not drawn: %s", path, t_ns / 1e9,
                                outcome)
        except Exception as e:  # an input that does not decode or apply: the rest is shown
            log.warning("viewer: %s: a spawn at %.3f s cannot be rebuilt (%s); its entities are not drawn", path,
                        t_ns / 1e9, e)


def _files(info: Any) -> str:
    return ", ".join(str(f) for f in info.files) or str(info.path)


def _truth_name(entity: str, part: str | None, frame: str, robots: set[str]) -> str | None:
    """The ground truth's child frame of a layout's frame: each frame of a robot or a person, the one frame of an
    object (:func:`sigcore.record.recorder.truth_frame`)."""
    from sigcore.record.recorder import truth_frame

    if entity not in robots and part is not None:
        return None
    return truth_frame(entity, frame, entity in robots)


def _scene_of(world: Any, backend: str, path: Path) -> Any:
    """A simulation of ``world`` (never stepped: its scene, publications and the world file's poses), on the
    recorded backend, or on MuJoCo when that one is not installed here."""
    from sigcore import plugins
    from sigcore.sim import Simulation

    try:
        return Simulation(world, backend)
    except plugins.PluginError:
        if backend == "mujoco":
            raise ViewerError(f"{path}: the backend 'mujoco' is not installed: the scene cannot be built") from None
        log.warning("viewer: the recording's backend %r is not installed; its scene is built with 'mujoco'", backend)
        return _scene_of(world, "mujoco", path)
    except SigcoreError as e:
        raise ViewerError(f"{path}: the recorded world cannot be rebuilt: {e}") from None


def _read(recording: RecordingFile, layout: SceneLayout, kinds: dict[str, str], base: np.ndarray,
          names: list[str | None], shown: list[Publication], overlays: list[Publication], dt_ns: int, world: str,
          stop: Callable[[], bool]) -> Recorded:
    """One pass over the messages: the ground truth, the shown publications' lines, scans and grids."""
    from sigcore.record.reader import TruthReader, decode_input

    path, info = recording.path, recording.info
    truth_topic, inputs_topic = recording.truth_topic, recording.inputs_topic
    serializer = recording.serializer
    by_topic = {p.full_topic: p for p in shown}
    for p in shown:
        if p.model is not None:
            serializer.register(p.full_type, p.model)
    recorded = {t.name: t.typename for t in info.topics}
    # the declared publications only, as live (a transport's own scans, recorded too, would be drawn twice)
    scans = {p.full_topic: Serialized(p.msg_type) for p in overlays if p.msg_type == _SCAN and p.full_topic
             in recorded}
    grids = {p.full_topic: Serialized(p.msg_type) for p in overlays if p.msg_type == _GRID and p.full_topic
             in recorded}
    wanted = {truth_topic, inputs_topic, *by_topic, *scans, *grids} & set(recorded)

    frame_of = {name: i for i, name in enumerate(names) if name is not None}
    reader = TruthReader(serializer)
    maps: dict[int, tuple[tuple[str, ...], np.ndarray, np.ndarray]] = {}  # id(children) -> (children, src, dst)
    times: list[int] = []
    rows: list[np.ndarray] = []
    present: list[np.ndarray] = []
    seen_names: set[str] = set()
    lines = Lines()
    bad: set[str] = set()
    order = 0
    for topic, t_ns, data in recording.messages(wanted):
        order += 1
        if order % 4096 == 0 and stop():
            raise Interrupted(f"{path}: reading stopped")
        if topic == truth_topic:
            try:
                children, values = reader.read(data)
            except Exception as e:  # a damaged message: the others are shown
                if topic not in bad:
                    bad.add(topic)
                    log.warning("viewer: a ground-truth message of %s at %.3f s cannot be read (%s)", path,
                                t_ns / 1e9, e)
                continue
            mapped = maps.get(id(children))
            if mapped is None or mapped[0] is not children:
                if len(maps) > 64:  # messages decoded one by one (not the recorder's layout): no reuse
                    maps.clear()
                index: dict[str, int] = {}
                for k, child in enumerate(children):
                    index.setdefault(child, k)
                pairs = [(index[name], i) for i, name in enumerate(names) if name is not None and name in index]
                src = np.array([p[0] for p in pairs], dtype=np.intp)
                dst = np.array([p[1] for p in pairs], dtype=np.intp)
                mapped = maps[id(children)] = (children, src, dst)
                seen_names.update(children)
            _, src, dst = mapped
            row = base.copy()
            row[dst] = values[src]
            mask = np.zeros(len(base), dtype=bool)
            mask[dst] = True
            times.append(t_ns)
            rows.append(row)
            present.append(mask)
        elif topic in by_topic:
            publication = by_topic[topic]
            try:
                value = message_fields(serializer.deserialize(publication.full_type, data))
            except Exception as e:  # a message that does not decode: the others are shown
                if topic not in bad:
                    bad.add(topic)
                    log.warning("viewer: a message of %s in %s cannot be decoded (%s)", topic, path, e)
                continue
            line = publication.display_text(value)
            item = (t_ns, order, line)
            if publication.display == "value":
                lines.values.setdefault(topic, []).append(item)
            elif publication.display == "log":
                lines.log.append(item)
            else:
                lines.results.setdefault(topic, []).append(item)
        elif topic == inputs_topic:
            try:
                kind = decode_input(serializer, data).kind
            except Exception:  # an input that does not decode changes nothing shown
                continue
            if kind == "reset":
                lines.resets.append((t_ns, order))
            elif kind == "world":
                lines.worlds.append((t_ns, order))
        elif topic in scans:
            scans[topic].times.append(t_ns)
            scans[topic].data.append(data)
        elif topic in grids:
            grids[topic].times.append(t_ns)
            grids[topic].data.append(data)
    if not times:
        raise ViewerError(f"{_files(info)} holds no readable ground truth on {truth_topic}: there is nothing to show "
                          "the scene with")
    # a cut recording is read in file order: sort by log time (stable, so the order within one time is kept)
    sort = np.argsort(np.asarray(times, dtype=np.int64), kind="stable")
    for texts in (*lines.values.values(), lines.log, *lines.results.values()):
        texts.sort(key=lambda item: (item[0], item[1]))
    for marks in (lines.resets, lines.worlds):
        marks.sort()
    for kept in (*scans.values(), *grids.values()):
        ordered = sorted(range(len(kept.times)), key=kept.times.__getitem__)  # stable: file order within a time
        kept.times, kept.data = [kept.times[k] for k in ordered], [kept.data[k] for k in ordered]
    pose_array = np.stack(rows)[sort]
    present_array = np.stack(present)[sort]
    tracked = np.asarray(present_array.any(axis=0), dtype=bool)
    untracked = sorted(n for n in seen_names if n not in frame_of)
    everything = [times[0], times[-1]]
    for store in (*lines.values.values(), lines.log, *lines.results.values()):
        if store:
            everything += [store[0][0], store[-1][0]]
    start_ns = min(everything)
    end_ns = max(max(everything), start_ns)
    return Recorded(path, world, recording.facts.get("backend", "?"), dt_ns, layout, kinds, base, tracked,
                    np.asarray(times, dtype=np.int64)[sort], pose_array, present_array, lines,
                    {k: v for k, v in scans.items() if v.times}, {k: v for k, v in grids.items() if v.times},
                    start_ns, end_ns, list(info.problems), untracked)


def message_fields(message: Any) -> Any:
    """A decoded message as the field dictionary a publisher pushes (nested messages as dictionaries, arrays as
    lists)."""
    if dataclasses.is_dataclass(message) and not isinstance(message, type):
        return {f.name: message_fields(getattr(message, f.name)) for f in dataclasses.fields(message)
                if not f.name.startswith("__")}
    if isinstance(message, np.ndarray):
        return message.tolist()
    if isinstance(message, list | tuple):
        return [message_fields(item) for item in message]
    return message
