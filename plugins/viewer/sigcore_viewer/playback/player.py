"""The player of a recording (``sigcore view DIR``): its clock, the person's requests from the panel (play, pause,
speed, seek, select, overlays), the timeline the panel shows and the :class:`~sigcore_viewer.snapshot.Snapshot` of the
current moment, built from the recorded data (:mod:`sigcore_viewer.playback.recorded`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from sigcore.geometry import quat_yaw
from sigcore.text import clip, quote

from ..overlays import grid_image, no_grid, scan_points
from ..scenebuild import layout_of
from ..snapshot import Snapshot
from .clock import SPEEDS, Clock, speed_name
from .recorded import Recorded, message_fields


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
        recorded: The recording (:func:`~sigcore_viewer.playback.recorded.load`).
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
                    scans.append(message_fields(_decode(kept.typename, kept.data[k])))
            snap.scan = scan_points(r.layout, scans, poses)
        for topic, kept in r.grids.items():
            k = kept.index_at(t_ns)
            if self._grids_sent.get(topic) != k:
                self._grids_sent[topic] = k
                grid = grid_image(message_fields(_decode(kept.typename, kept.data[k]))) if k >= 0 else None
                snap.grid = grid if grid is not None else no_grid()
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


def loading(path: Path, wall: float) -> Snapshot:
    """The snapshot shown while the recording is read (an empty scene)."""
    return Snapshot(0, 0.0, wall, layout_of(None), np.empty((0, 7)), f"**reading the recording** `{path}`…",
                    {"score": "", "events": "", "result": "", "selection": "", "notes": ""}, [], [])
