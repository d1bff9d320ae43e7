"""The viewer's side panel: the run's controls, the task's score and events, messages to agents, the selected
entity, the overlays. It lives in the viewer's process: its callbacks (viser's threads) only send the person's
requests to the simulation, as plain tuples (``("step", 100)``, ``("send", agent, text)``...); :meth:`Panel.update`
(the push thread) shows a snapshot. One panel is shared by every browser: they all see and steer the same run.

For a recording (``sigcore view DIR``, :meth:`Panel.playback`) the "Run" folder becomes "Playback": play, pause, a
time slider to scrub, the speed, jumps to the start and the end; the live run's controls are hidden or disabled."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .commands import PACES

if TYPE_CHECKING:
    from .playback import Timeline
    from .snapshot import Snapshot

NONE = "(none)"
HOLD = 0.6
"""Wall seconds after a person moved the time slider during which the playback does not move it (so that it does
not jump back under the person's pointer while the seek is on its way)."""


class Panel:
    """Builds the GUI on ``server`` and sends the person's requests with ``post``.

    Args:
        server: The viser server.
        post: Sends a request to the simulation's process.
        overlays: The overlay switches of the viewer's process (changed here; the simulation is told too).
        on_viser: Runs a callable on viser's event-loop thread (:meth:`~sigcore_viewer.front.Front.on_viser`): what
            a callback changes in viser goes through it (viser calls the callbacks on its thread pool).
    """

    def __init__(self, server: Any, post: Callable[[tuple[Any, ...]], None], overlays: dict[str, bool],
                 on_viser: Callable[..., Any]) -> None:
        gui = server.gui
        self._server = server
        self._post = post
        self._on_viser = on_viser
        self._overlays = overlays
        self._texts: dict[str, str] = {}
        self._options: dict[str, tuple[str, ...]] = {}
        self._drag: Any = None
        self._drag_name: str | None = None
        self._images: dict[str, Any] = {}
        self.time: Any = None  # a recording's timeline (playback)
        self.speed: Any = None
        self._touched = 0.0

        self.notes = gui.add_markdown("")
        self.run = gui.add_folder("Run")
        with self.run:
            self.status = gui.add_markdown("starting")
            self.play = gui.add_button("Play", hint="run the simulation")
            self.pause = gui.add_button("Pause", hint="pause the simulation")
            self.steps = gui.add_number("Steps", initial_value=100, min=1, max=100000, step=1)
            self.step = gui.add_button("Step", hint="pause, then advance this many steps")
            self.reset = gui.add_button("Reset", hint="put the world back as it was at the start")
            self.pace = gui.add_dropdown("Pace", tuple(PACES), initial_value="real time")
        with gui.add_folder("Task"):
            self.result = gui.add_markdown("")
            self.score = gui.add_markdown("")
            self.events = gui.add_markdown("")
            self.table = gui.add_markdown("")  # the features' report once the run has ended (the score table)
        self.messages = gui.add_folder("Message")
        with self.messages:
            self.to = gui.add_dropdown("To", (NONE,), initial_value=NONE)
            self.message = gui.add_text("Message", initial_value="")
            self.send = gui.add_button("Send", hint="deliver the text to the agent (on_recv_msg, <agent>_onRecvMsg)")
        with gui.add_folder("Selection"):
            self.entity = gui.add_dropdown("Entity", (NONE,), initial_value=NONE)
            self.drag = gui.add_checkbox("Drag handle", initial_value=False,
                                         hint="move the selected entity with a handle in the scene")
            self.selection = gui.add_markdown("")
        with gui.add_folder("Overlays", expand_by_default=False):
            self.switches = {key: gui.add_checkbox(label, initial_value=overlays[key]) for key, label in (
                ("names", "Names"), ("frames", "TF frames"), ("scan", "Lidar scans"), ("contacts", "Contacts"),
                ("map", "Map (SLAM)"))}
        self._cameras = gui.add_folder("Cameras", expand_by_default=False, visible=False)

        self.play.on_click(lambda _e: post(("play",)))
        self.pause.on_click(lambda _e: post(("pause",)))
        self.step.on_click(lambda _e: post(("step", self.steps.value)))
        self.reset.on_click(lambda _e: post(("reset",)))
        # a person's choice only: showing the run's pace (update) assigns the value too, which calls this with no
        # client, and echoing that could undo a newer change made meanwhile (by the command line, another browser)
        self.pace.on_update(lambda e: post(("pace", self.pace.value)) if e.client_id is not None else None)
        self.send.on_click(lambda _e: post(("send", "" if self.to.value == NONE else self.to.value,
                                            self.message.value)))
        self.entity.on_update(lambda _e: self._entity_picked())
        self.drag.on_update(lambda _e: self._entity_picked())
        for key, box in self.switches.items():
            box.on_update(lambda _e, key=key, box=box: self._switched(key, bool(box.value)))

    def _switched(self, key: str, on: bool) -> None:
        self._overlays[key] = on
        self._post(("overlay", key, on))

    def show_switch(self, key: str, on: bool) -> None:
        """The simulation's process turned overlay ``key`` on or off: show the switch so."""
        box = self.switches.get(key)
        if box is not None and bool(box.value) != on:
            box.value = on

    def _entity_picked(self) -> None:
        name = self.entity.value
        if name != NONE:
            self._post(("select", name))
        else:
            self._on_viser(self._hide_drag)

    # ------------------------------------------------------------------ a recording
    def playback(self, timeline: Timeline) -> None:
        """The viewer plays a recording back: the "Run" folder becomes the player (play, pause, the time slider, the
        speed, to start, to end); step, reset, the pace and messages are hidden, dragging and overlays the recording
        cannot show are disabled, and a note at the top says what is shown."""
        gui = self._server.gui
        post = self._post
        self.run.label = "Playback"
        for handle in (self.steps, self.step, self.reset, self.pace, self.messages):
            handle.visible = False
        self.play.hint = "play the recording from the time shown (from the start at the end)"
        self.pause.hint = "hold the recording at the time shown"
        self.drag.disabled = True
        self.drag.value = False
        self.drag.hint = "a recording cannot be changed: dragging belongs to live runs"
        for key, box in self.switches.items():
            if not timeline.overlays.get(key, False):
                box.disabled = True
                box.hint = "not in this recording"
        gui.add_markdown(timeline.note, order=self.notes.order - 0.5)
        with self.run:
            start, end = float(timeline.start), float(timeline.end)
            self.time = gui.add_slider("Time [s]", min=start, max=end, step=0.01, initial_value=start,
                                       hint="simulated time: drag to scrub, or type a time")
            self.speed = gui.add_dropdown("Speed", timeline.speeds, initial_value=timeline.speed,
                                          hint="simulated seconds per second of wall time")
            to_start = gui.add_button("To start", hint="jump to the first moment of the recording")
            to_end = gui.add_button("To end", hint="jump to the last moment of the recording")
        slider, speed = self.time, self.speed

        def seek(event: Any) -> None:
            if event.client_id is not None:  # a person's move (showing the playback's time calls this too)
                self._touched = time.monotonic()
                post(("seek", float(slider.value)))
        slider.on_update(seek)
        speed.on_update(lambda e: post(("speed", speed.value)) if e.client_id is not None else None)
        to_start.on_click(lambda _e: post(("seek", "start")))
        to_end.on_click(lambda _e: post(("seek", "end")))

    def _show_timeline(self, timeline: tuple[float, bool, str]) -> None:
        """Move the slider to the playback's time (unless a person just moved it) and show its speed."""
        t, _, speed = timeline
        slider = self.time
        if slider is None:
            return
        if time.monotonic() - self._touched > HOLD:
            value = min(max(round(t, 2), float(slider.min)), float(slider.max))
            if abs(float(slider.value) - value) > 1e-9:
                slider.value = value
        if self.speed is not None and speed in self.speed.options and self.speed.value != speed:
            self.speed.value = speed

    # ------------------------------------------------------------------ told by the simulation's process
    def selected(self, name: str, pose: tuple[Any, Any] | None) -> None:
        """``name`` was selected: show it in the list and put the drag handle on it (if it is on)."""
        if self.entity.value != name and name in self.entity.options:
            self.entity.value = name
        if not self.drag.value or pose is None:
            self._hide_drag()
            return
        position, wxyz = pose
        if self._drag is None or self._drag_name != name:
            self._hide_drag()
            self._drag = self._server.scene.add_transform_controls("/sigcore_drag", scale=0.4,
                                                                   position=position, wxyz=wxyz)
            self._drag_name = name
            handle = self._drag

            def moved(_e: Any, name: str = name) -> None:
                self._post(("move", name, [float(x) for x in handle.position], [float(x) for x in handle.wxyz]))
            handle.on_update(moved)
        else:
            self._drag.position, self._drag.wxyz = position, wxyz

    def _hide_drag(self) -> None:
        if self._drag is not None:
            self._drag.remove()
            self._drag, self._drag_name = None, None

    # ------------------------------------------------------------------ from the push thread
    def update(self, snap: Snapshot) -> None:
        """Show ``snap``'s texts, lists and images (only what changed is sent)."""
        self._text(self.status, "status", snap.status)
        self._text(self.notes, "notes", snap.texts["notes"])
        self._text(self.score, "score", snap.texts["score"])
        self._text(self.events, "events", "**events**  \n" + snap.texts["events"])
        result = snap.texts["result"]
        self._text(self.result, "result", f"### {result}" if result else "")
        self._text(self.selection, "selection", snap.texts["selection"])
        table = snap.texts.get("table", "")
        self._text(self.table, "table", f"**at the end**\n```text\n{table}\n```" if table else "")
        if snap.ended and not self._texts.get("ended"):  # the run is over: its controls do nothing any more
            self._texts["ended"] = "yes"
            for control in (self.play, self.pause, self.steps, self.step, self.reset, self.pace, self.send):
                control.disabled = True
        if self._texts.get("pace") != snap.pace:  # the pace the run has (the command line's, another browser's)
            self._texts["pace"] = snap.pace
            if snap.pace in self.pace.options and self.pace.value != snap.pace:
                self.pace.value = snap.pace
        if snap.timeline is not None:
            self._show_timeline(snap.timeline)
        self._list(self.to, "to", snap.agents)
        self._list(self.entity, "entity", [NONE, *snap.entities])
        if snap.images:
            self._cameras.visible = True
            for topic, image in snap.images.items():
                if topic in self._images:
                    self._images[topic].image = image
                else:
                    with self._cameras:
                        self._images[topic] = self._server.gui.add_image(image, label=topic)

    def _text(self, handle: Any, key: str, text: str) -> None:
        if self._texts.get(key) != text:
            self._texts[key] = text
            handle.content = text

    def _list(self, handle: Any, key: str, names: list[str]) -> None:
        options = tuple(names) if names else (NONE,)
        if self._options.get(key) != options:
            self._options[key] = options
            keep = handle.value if handle.value in options else options[0]
            handle.options = options
            handle.value = keep
