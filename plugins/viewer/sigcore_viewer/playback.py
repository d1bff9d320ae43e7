"""Playing a recording back in the web viewer (``sigcore view DIR``): what a recording shows at each moment.

A recording made by ``sigcore run --record`` (:mod:`sigcore.record`) holds everything the viewer needs:

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

:func:`load` reads all of it once; :class:`Player` is the playback: the clock (play, pause, speed, seek), the
person's requests and the :class:`~sigcore_viewer.viewer.Snapshot` of a moment. It runs in the process that called
:meth:`~sigcore_viewer.viewer.WebViewer.play_recording`; the viewer's process shows the snapshots as for a live run.
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
from sigcore.geometry import quat_yaw
from sigcore.text import clip, quote

from .exceptions import Interrupted
from .scenebuild import SceneLayout, layout_of

if TYPE_CHECKING:
    from sigcore.publish import Publication
    from sigcore.record.reader import RecordingFile

    from .viewer import Snapshot

log = logging.getLogger("sigcore.viewer")

SPEEDS: dict[str, float] = {"0.25x": 0.25, "0.5x": 0.5, "1x": 1.0, "2x": 2.0, "4x": 4.0, "10x": 10.0}
"""The playback speeds a person may pick (simulated seconds per wall second)."""

LOG_SHOWN = 15
"""Events shown (newest first), as live."""

_SCAN = "sensor_msgs/msg/LaserScan"
_GRID = "nav_msgs/msg/OccupancyGrid"


# ---------------------------------------------------------------------- what a recording holds
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
        robots = {name for name, kind in kinds.items() if kind == "robot"}
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
    """The ground truth's child frame of a layout's frame: each frame of a robot, the one frame of any other
    entity (:func:`sigcore.record.recorder.truth_frame`)."""
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
                value = _fields(serializer.deserialize(publication.full_type, data))
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


def _fields(message: Any) -> Any:
    """A decoded message as the field dictionary a publisher pushes (nested messages as dictionaries, arrays as
    lists)."""
    if dataclasses.is_dataclass(message) and not isinstance(message, type):
        return {f.name: _fields(getattr(message, f.name)) for f in dataclasses.fields(message)
                if not f.name.startswith("__")}
    if isinstance(message, np.ndarray):
        return message.tolist()
    if isinstance(message, list | tuple):
        return [_fields(item) for item in message]
    return message


# ---------------------------------------------------------------------- the playback
class Clock:
    """The playback's time [ns of simulated time] in ``[start, end]``: paused or playing at a speed; it stops at
    the end. Every method takes the wall clock now (``time.perf_counter()``) [s]."""

    def __init__(self, start_ns: int, end_ns: int) -> None:
        self.start_ns, self.end_ns = start_ns, end_ns
        self._t = start_ns
        self._wall = 0.0
        self.playing = False
        self.speed = 1.0

    def now(self, wall: float) -> int:
        """The time at ``wall``; reaching the end pauses there."""
        if self.playing:
            t = self._t + round((wall - self._wall) * self.speed * 1e9)
            if t >= self.end_ns:
                self._t, self.playing = self.end_ns, False
            else:
                return t
        return self._t

    def play(self, wall: float) -> None:
        """Play on from now (from the start when at the end)."""
        t = self.now(wall)
        self._t = self.start_ns if t >= self.end_ns else t
        self._wall = wall
        self.playing = self.end_ns > self.start_ns

    def pause(self, wall: float) -> None:
        self._t = self.now(wall)
        self.playing = False

    def seek(self, t_ns: int, wall: float) -> None:
        """Go to ``t_ns`` (within the recording), playing on from there if playing."""
        self._t = min(max(int(t_ns), self.start_ns), self.end_ns)
        self._wall = wall
        if self._t >= self.end_ns:
            self.playing = False

    def set_speed(self, speed: float, wall: float) -> None:
        self._t = self.now(wall)
        self._wall = wall
        self.speed = speed


def speed_name(speed: float) -> str:
    return next((name for name, value in SPEEDS.items() if value == speed), f"{speed:g}x")


@dataclass(frozen=True)
class Timeline:
    """What the panel needs to show a recording's timeline (sent to the viewer's process once).

    Attributes:
        start, end: The recording's first and last moment [s].
        speeds: The speeds to choose from; speed: the one at the start.
        note: The line at the top of the panel (what is shown, what is off, a cut recording).
        overlays: Whether each overlay can show something of this recording.
    """

    start: float
    end: float
    speeds: tuple[str, ...]
    speed: str
    note: str
    overlays: dict[str, bool]


class Player:
    """The playback of one recording: its clock, the person's requests, the snapshot of the current moment.

    Args:
        recorded: The recording (:func:`load`).
        overlays: The overlay switches (kept in step with the panel's).
    """

    def __init__(self, recorded: Recorded, overlays: dict[str, bool]) -> None:
        self.recorded = recorded
        self.clock = Clock(recorded.start_ns, recorded.end_ns)
        self.overlays = dict(overlays)
        self.selected: str | None = None
        self.notes: list[str] = []
        self.dirty = True
        """Something changed that a snapshot must show (a request, a seek)."""
        self._layout_sent = False
        self._grids_sent: dict[str, int] = {}

    @property
    def playing(self) -> bool:
        return self.clock.playing

    def timeline(self) -> Timeline:
        r = self.recorded
        note = (f"**Recording** `{r.path.name}`: world `{r.world}`, {(r.end_ns - r.start_ns) / 1e9:.2f} s recorded "
                f"on {r.backend}. Step, reset, pace, messages to agents and dragging belong to live runs: they are "
                "off here.")
        if r.problems:
            note += f"  \n**The recording is cut**: it is shown up to t = {r.end_ns / 1e9:.2f} s."
        if r.untracked:
            note += (f"  \n{len(r.untracked)} frame(s) of entities added while running are not drawn (their spawn "
                     "could not be rebuilt from the input log).")
        return Timeline(r.start_ns / 1e9, r.end_ns / 1e9, tuple(SPEEDS), speed_name(self.clock.speed), note,
                        {"names": True, "frames": True, "scan": bool(r.scans), "contacts": False,
                         "map": bool(r.grids)})

    # ------------------------------------------------------------------ the person's requests
    def request(self, message: tuple[Any, ...], wall: float) -> None:
        """Act on a request from the panel (``("play",)``, ``("seek", 12.5)``, ``("speed", "2x")``...); one this
        playback does not take becomes a note."""
        kind, args = message[0], message[1:]
        clock = self.clock
        self.dirty = True
        try:
            if kind == "play" and not args:
                clock.play(wall)
            elif kind == "pause" and not args:
                clock.pause(wall)
            elif kind == "seek" and len(args) == 1:
                target = args[0]
                if target == "start":
                    clock.seek(clock.start_ns, wall)
                elif target == "end":
                    clock.seek(clock.end_ns, wall)
                else:
                    value = float(target)
                    if not math.isfinite(value):
                        raise ValueError(target)
                    clock.seek(round(value * 1e9), wall)
            elif kind == "speed" and len(args) == 1:
                if args[0] not in SPEEDS:
                    self._note(f"unknown speed {quote(str(args[0]))}; valid: {', '.join(SPEEDS)}", wall)
                else:
                    clock.set_speed(SPEEDS[args[0]], wall)
            elif kind == "select" and len(args) == 1:
                name = str(args[0])
                if name not in self.recorded.kinds:
                    self._note(f"no entity {quote(name)} to select; entities: {', '.join(self.recorded.kinds)}", wall)
                else:
                    self.selected = name
            elif kind == "overlay" and len(args) == 2:
                key = str(args[0])
                if key not in self.overlays:
                    self._note(f"unknown overlay {quote(key)}; valid: {', '.join(self.overlays)}", wall)
                else:
                    self.overlays[key] = bool(args[1])
            elif kind in ("step", "reset", "pace", "send", "move"):
                self._note(f"{kind} belongs to live runs: a recording only plays back", wall)
            else:
                self._note(f"the viewer sent a request the playback does not know: {clip(repr(message), 80)}", wall)
        except (TypeError, ValueError):
            self._note(f"the viewer sent a request the playback does not know: {clip(repr(message), 80)}", wall)

    def _note(self, text: str, wall: float) -> None:
        self.notes.append(f"t = {self.clock.now(wall) / 1e9:.2f} s: {text}")
        del self.notes[:-5]

    # ------------------------------------------------------------------ what is shown
    def snapshot(self, wall: float) -> Snapshot:
        """The snapshot of the moment ``wall`` stands for (the first one carries the layout). A snapshot while
        paused is exact (every frame sent as recorded); while playing, frames that moved less than the viewer's
        threshold are not sent again, as live."""
        from .viewer import Snapshot, _grid_image, scan_points

        r = self.recorded
        t_ns = self.clock.now(wall)
        poses, hidden = r.poses_at(t_ns)
        layout = None
        if not self._layout_sent:
            layout, self._layout_sent = r.layout, True
        texts = r.lines.at(t_ns)
        texts["selection"] = self._describe(poses, hidden, t_ns)
        texts["notes"] = "  \n".join(reversed(self.notes))
        clock = self.clock
        t = t_ns / 1e9
        state = (f"playing ({speed_name(clock.speed)})" if clock.playing else
                 "paused at the end" if t_ns >= clock.end_ns else "paused")
        status = (f"**{state}** · recording `{r.path.name}` · world `{r.world}` · t = {t:.2f} s of "
                  f"{clock.start_ns / 1e9:.2f}–{clock.end_ns / 1e9:.2f} s · step {t_ns // r.dt_ns}")
        snap = Snapshot(t_ns // r.dt_ns, t, wall, layout, poses, status, texts, [], list(r.kinds))
        snap.exact = not clock.playing
        snap.hidden = hidden
        snap.timeline = (t, clock.playing, speed_name(clock.speed))
        if self.overlays["scan"] and r.scans:
            scans = []
            for kept in r.scans.values():
                k = kept.index_at(t_ns)
                if k >= 0:
                    scans.append(_fields(_decode(kept.typename, kept.data[k])))
            snap.scan = scan_points(r.layout, scans, poses)
        for topic, kept in r.grids.items():
            k = kept.index_at(t_ns)
            if self._grids_sent.get(topic) != k:
                self._grids_sent[topic] = k
                grid = _grid_image(_fields(_decode(kept.typename, kept.data[k]))) if k >= 0 else None
                snap.grid = grid if grid is not None else _no_grid()
        self.dirty = False
        return snap

    def _describe(self, poses: np.ndarray, hidden: np.ndarray, t_ns: int) -> str:
        """The selected entity's pose in the ground truth at ``t_ns``."""
        name = self.selected
        if name is None:
            return "click an entity, or pick one above"
        layout = self.recorded.layout
        try:
            i = layout.parts.index((name, None))
        except ValueError:
            return f"{quote(name)} has no frame in the scene"
        lines = [f"**{name}** ({self.recorded.kinds.get(name, '?')})"]
        if hidden[i]:
            lines.append(f"not in the world at t = {t_ns / 1e9:.2f} s")
            return "  \n".join(lines)
        pos, quat = poses[i, :3], poses[i, 3:]
        w, x, y, z = quat
        lines.append(f"position: {pos[0]:.3f} {pos[1]:.3f} {pos[2]:.3f} m")
        yaw = math.degrees(quat_yaw(quat))
        lines.append(f"orientation (w x y z): {w:.3f} {x:.3f} {y:.3f} {z:.3f} (yaw {yaw:.1f}°)")
        source = "the ground truth" if self.recorded.tracked[i] else "the world file (no ground truth of it)"
        lines.append(f"from {source} at t = {t_ns / 1e9:.2f} s")
        return "  \n".join(lines)


_SERIALIZER: Any = None


def _decode(typename: str, data: bytes) -> Any:
    global _SERIALIZER
    if _SERIALIZER is None:
        from sigcore.record.serialize import Serializer

        _SERIALIZER = Serializer()
    return _SERIALIZER.deserialize(typename, data)


def _no_grid() -> tuple[np.ndarray, float, float, np.ndarray, np.ndarray]:
    """No map at this moment: an empty image (the map shown is removed)."""
    return np.zeros((0, 0, 3), dtype=np.uint8), 0.0, 0.0, np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])


def loading(path: Path, wall: float) -> Snapshot:
    """The snapshot shown while the recording is read (an empty scene)."""
    from .viewer import Snapshot

    return Snapshot(0, 0.0, wall, layout_of(None), np.empty((0, 7)), f"**reading the recording** `{path}`…",
                    {"score": "", "events": "", "result": "", "selection": "", "notes": ""}, [], [])
