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

import logging
from dataclasses import dataclass, field
from itertools import takewhile
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..sim.exceptions import ReplayError
from ..sim.inputs import Input, refusal
from ..transport import Transport
from .reader import RecordingFile, TruthReader, decode_input, open_recording
from .recorder import truth_frames
from .verify import COMPARED_TOPICS

if TYPE_CHECKING:
    from ..api.deferred import Deferred
    from ..api.table import ApiEntry
    from ..sim.events import Subscription
    from ..sim.simulation import Simulation

log = logging.getLogger("sigcore.record")

__all__ = ["Recording", "ReplayError", "ReplayPlan", "Replayer", "compare", "describe_inputs", "load_recording",
           "plan_replay", "poses_now"]


@dataclass
class Recording(RecordingFile):
    """What a replay needs from a recording (:func:`load_recording`): the file (:class:`RecordingFile`), its input
    log, its ground truth and the messages of the compared topics."""

    inputs: list[Input] = field(default_factory=list)
    """Every command applied from outside, in the order applied."""
    truth: list[tuple[int, dict[str, np.ndarray]]] = field(default_factory=list)
    """Every ground-truth message in the order written: (step, child frame -> x, y, z, qw, qx, qy, qz)."""
    topics: dict[str, list[tuple[int, bytes]]] = field(default_factory=dict)
    """The recorded messages of the compared topics (the referee's, :data:`~sigcore.record.verify.COMPARED_TOPICS`)
    that the recording holds: topic -> [(log time [ns], CDR bytes)] in the order written."""

    @property
    def final_step(self) -> int:
        """The run's last step (that of the last ground truth, written when the run ended)."""
        return self.truth[-1][0] if self.truth else self.start_step


def load_recording(path: Path) -> Recording:
    """Read what a replay needs from the recording ``path`` (through :func:`~sigcore.record.reader.open_recording`).

    Raises:
        ReplayError: the recording is cut, foreign, or was not made by ``sigcore run --record`` (naming why).
    """
    file = open_recording(path)
    if file.info.problems:
        raise ReplayError(f"{path} cannot be replayed: {file.info.problems[0]}")
    dt_ns = file.dt_ns
    inputs: list[Input] = []
    truth: list[tuple[int, dict[str, np.ndarray]]] = []
    reader = TruthReader(file.serializer)
    compared = {t.name for t in file.info.topics} & set(COMPARED_TOPICS)
    topics: dict[str, list[tuple[int, bytes]]] = {t: [] for t in compared}
    # in the order written (the order the commands were applied), not sorted by log time
    for topic, t_ns, data in file.messages([file.inputs_topic, file.truth_topic, *compared], written_order=True):
        if topic == file.inputs_topic:
            try:
                inputs.append(decode_input(file.serializer, data))
            except ValueError as e:
                raise ReplayError(f"{path}: the input at {t_ns / 1e9:.3f} s does not decode: {e}") from None
        elif topic == file.truth_topic:
            truth.append((t_ns // dt_ns, reader.poses(data)))
        else:
            topics[topic].append((t_ns, bytes(data)))
    return Recording(file.path, file.info, file.facts, file.attachments, inputs, truth, topics)


@dataclass(frozen=True)
class ReplayPlan:
    """How far a replay goes (:func:`plan_replay`).

    Attributes:
        target: The step the replay stops at.
        final: The recorded run's last step.
        whole: Whether it replays the whole run (the commands noted at its last step, which the run applied as it
            stopped, are applied when the replay stops there).
    """

    target: int
    final: int
    whole: bool

    def replayer(self, recording: Recording) -> Replayer:
        """The transport that applies the recorded commands up to :attr:`target`."""
        return Replayer(recording.inputs, until=None if self.whole else self.target,
                        end=self.final if self.whole else None)

    def check_start(self, recording: Recording, sim: Simulation) -> None:
        """Refuse a simulation that does not start where the recorded run did.

        Raises:
            ReplayError: naming both steps.
        """
        if sim.step_count != recording.start_step:
            raise ReplayError(f"the recording starts at step {recording.start_step}, a new simulation at "
                              f"{sim.step_count}")


def plan_replay(recording: Recording, until: int | None = None) -> ReplayPlan:
    """Plan a replay of ``recording`` to its end or to step ``until``: refused before anything runs when it cannot
    reproduce the run.

    Raises:
        ReplayError: ``until`` is past the recording's end or past its first world (world loads are not replayed),
            or a command before the target (or, for the whole run, a world load) cannot be applied again; the message
            says which and what would be valid.
    """
    final = recording.final_step
    target = final if until is None else until
    load = next((i for i in recording.inputs if i.kind == "world"), None)  # --until counts the first world's steps
    if until is not None and load is not None and until > load.step:
        raise ReplayError(f"--until {until}: the run's first world ended at step {load.step}, where it applied "
                          f"'{load.args.get('what') or 'world'}' (world loads are not replayed); --until "
                          f"{load.step} replays up to it")
    if target > final:
        raise ReplayError(f"--until {until}: the recording ends at step {final} "
                          f"(t = {final * recording.dt_ns / 1e9:.3f} s)")
    # the commands applied before the target, in the log's order (a world load would restart the step count: the
    # whole run's replay stops at one wherever it is)
    applied = list(takewhile(lambda i: i.step < target, recording.inputs))
    blocked = next((why for i in applied if (why := refusal(i)) is not None), None)
    if blocked is None and until is None:
        blocked = next((why for i in recording.inputs if i.kind == "world" and (why := refusal(i)) is not None),
                       None)
    if blocked is not None:
        raise ReplayError(blocked)
    return ReplayPlan(target, final, until is None)


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
