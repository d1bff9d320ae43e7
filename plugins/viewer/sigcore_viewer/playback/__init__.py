"""Playing a recording back in the web viewer (``sigcore view DIR``): what a recording shows at each moment.

:func:`load` (:mod:`.recorded`) reads all of a recording once, through :mod:`sigcore.record.reader`: the recorded
world's scene, its ground truth, the publications a viewer shows as text, scans and maps. :class:`Player`
(:mod:`.player`) is the playback: the clock (:mod:`.clock`: play, pause, speed, seek), the person's requests and the
:class:`~sigcore_viewer.snapshot.Snapshot` of a moment. It runs in the process that called
:meth:`~sigcore_viewer.viewer.WebViewer.play_recording`; the viewer's process shows the snapshots as for a live run.
"""

from __future__ import annotations

from ..exceptions import Interrupted
from .clock import SPEEDS, Clock, speed_name
from .player import Player, Timeline, loading
from .recorded import LOG_SHOWN, Lines, Recorded, Serialized, load

__all__ = ["LOG_SHOWN", "SPEEDS", "Clock", "Interrupted", "Lines", "Player", "Recorded", "Serialized", "Timeline",
           "load", "loading", "speed_name"]
