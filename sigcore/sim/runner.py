"""Run modes: as fast as possible, real time (or a factor of it), paused, stepped by a client (`sim.control`)."""

from __future__ import annotations

import logging
import time as _time
from collections.abc import Callable, Sequence
from contextlib import nullcontext
from dataclasses import dataclass, field

__all__ = ["RunControl", "RunReport", "run"]

from ..isolation import USER_ERRORS, describe
from ..transport import Transport
from .batching import BATCH_STEPS
from .control import RunControl, stop_on_signals
from .dispatch import ControllerFailure, SlowCallbacks
from .features import FeatureFailure
from .simulation import Simulation
from .startgate import StartGate

log = logging.getLogger("sigcore")


@dataclass(frozen=True)
class RunReport:
    """What a run did.

    Attributes:
        agents: Agent names by kind.
        steps: Steps taken in this run (in every world it ran: ``load_world`` may replace the world).
        sim_time: Simulated time at the end [s] (of the world loaded then).
        wall_time: Wall-clock duration of the run [s].
        failures: Controllers disabled during the run.
        summary: What each feature reported.
        sim_time_run: Simulated time covered by this run [s] (in every world it ran).
        stopped_by: Why the run ended before its duration or steps: ``"SIGINT"`` or ``"SIGTERM"`` for a signal,
            ``"request"`` for ``control.stop()`` called by a transport (QUITTING) or a feature (e.g. the referee at the
            end of its task), ``"error"`` when something that is not user code raised (see ``error``); None when
            it ran to its end.
        feature_failures: Features disabled during the run (or while reporting at its end).
        slow: Controllers whose callbacks took longer than the callback budget (``sim.entities.controllers.budget``).
        report_lines: The features' report lines (``Feature.report``).
        outcome: The world's verdict (:meth:`Simulation.outcome`): False if a feature says the task failed.
        error: When ``stopped_by`` is ``"error"``: what raised (``Type: message``), from the transport, the
            backend or an observer no feature owns (a bug in sigcore or in a transport plugin); its traceback is
            logged. None otherwise.
        results: What each feature gives a program (``Feature.results``), by feature name.
    """

    agents: dict[str, list[str]]
    steps: int
    sim_time: float
    wall_time: float
    failures: list[ControllerFailure] = field(default_factory=list)
    summary: dict[str, object] = field(default_factory=dict)
    sim_time_run: float = 0.0
    stopped_by: str | None = None
    feature_failures: list[FeatureFailure] = field(default_factory=list)
    slow: list[SlowCallbacks] = field(default_factory=list)
    report_lines: list[str] = field(default_factory=list)
    outcome: bool | None = None
    error: str | None = None
    results: dict[str, object] = field(default_factory=dict)

    @property
    def exit_code(self) -> int:
        """``sigcore run``'s exit code for this run: 3 when it stopped on an error outside user code, 1 when a
        feature says the task failed, else 0 (the table in ``docs/reliability.md``)."""
        return 3 if self.error is not None else 1 if self.outcome is False else 0

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second in this run."""
        return self.sim_time_run / self.wall_time if self.wall_time > 0 else float("inf")

    def as_dict(self) -> dict[str, object]:
        """The report as JSON-able values (``sigcore run --results FILE``): the figures, how the run ended, the
        verdict, what failed, and each feature's :attr:`results`."""
        return {"steps": self.steps, "sim_time": self.sim_time, "sim_time_run": self.sim_time_run,
                "wall_time": self.wall_time, "real_time_factor": self.real_time_factor if self.wall_time > 0 else None,
                "stopped_by": self.stopped_by, "error": self.error, "outcome": self.outcome,
                "agents": self.agents,
                "controller_failures": [{"agent": f.agent, "callback": f.callback, "time": f.time, "error": f.error}
                                        for f in self.failures],
                "feature_failures": [ff.line() for ff in self.feature_failures],
                "features": self.results}


def run(sim: Simulation, *, duration: float | None = None, steps: int | None = None,
        realtime_factor: float | None = None, control: RunControl | None = None,
        transport: Transport | Sequence[Transport] | None = None, progress: Callable[[Simulation], None] | None = None,
        progress_every: float = 0.5, started: Callable[[Simulation], None] | None = None,
        handle_signals: bool = True, gate: StartGate | None = None) -> RunReport:
    """Run ``sim`` until ``duration`` simulated seconds or ``steps`` steps have passed (or ``control.stopping``).

    The simulation is started (:meth:`Simulation.start`), then the transport; at the end the transport is stopped
    and then the simulation (:meth:`Simulation.stop`), however the run ends. SIGINT and SIGTERM end it like a
    ``control.stop`` (see :func:`sigcore.sim.control.stop_on_signals`), so the report is never lost; a second
    signal while stopping raises ``KeyboardInterrupt``. User code never ends a run: a controller or a feature that
    raises (or calls ``sys.exit``) is disabled and the run goes on. Anything else that raises while starting the
    transport or stepping (the transport, the backend, a bug) ends the run with ``stopped_by="error"`` and the
    error in the report; its traceback is logged.

    Args:
        sim: The simulation.
        duration: Simulated seconds to run [s]; None with ``steps`` None runs until stopped.
        steps: Number of steps to run (wins over ``duration``).
        realtime_factor: None for as fast as possible; 1.0 for real time; 2.0 for twice real time (the start value
            of ``control.realtime_factor``, which a viewer may change while running).
        control: The run's state (default: ``sim.control``, whose verbs transports and viewers call).
        transport: Serviced between steps (never during one); several (a transport and a viewer) are started in
            order, serviced in order (the first waits while the simulation is idle, the others are polled) and
            stopped in reverse order.
        progress: Called about every ``progress_every`` wall seconds.
        progress_every: Wall seconds between progress calls [s].
        started: Called once the simulation and the transport have started, before the first step.
        handle_signals: Turn SIGINT and SIGTERM into a stop request for the duration of the run (main thread only).
        gate: Holds a paused start until the named topics have their peers (``sigcore run --wait-for``); polled
            between steps while active; needs ``transport``.
    """
    control = control or sim.control
    control.set_pace(realtime_factor)
    transports = [] if transport is None else [transport] if isinstance(transport, Transport) else list(transport)
    target = steps if steps is not None else (round(duration / sim.dt) if duration is not None else None)
    worlds = sim.worlds
    start_step, start_time = worlds.elapsed_steps, worlds.elapsed_time  # a world loaded while running starts at step 0
    with stop_on_signals(control) if handle_signals else nullcontext():
        sim.start()
        try:
            error = None
            wall0 = _time.perf_counter()
            try:
                with _started(transports, sim):
                    if started is not None:
                        started(sim)
                    wall = _loop(sim, target, start_step, control, transports, progress, progress_every, gate)
            except USER_ERRORS as e:  # not user code (that is contained where it is called): a transport or a bug
                error = describe(e)
                log.error("the run stopped at t=%.3f s: %s", sim.time, error, exc_info=True)
                wall = _time.perf_counter() - wall0
        finally:
            sim.stop()
    kinds: dict[str, list[str]] = {}
    for name, handle in sim.entities.items():
        kinds.setdefault(handle.kind, []).append(name)
    stopped_by = "error" if error is not None else (control.stop_reason or "request") if control.stopping else None
    features, controllers = sim.features, sim.entities.controllers
    summary, lines = features.summary(), features.report_lines()
    outcome, results = features.outcome(), features.results()
    return RunReport(kinds, worlds.elapsed_steps - start_step, sim.time, wall, list(controllers.failures), summary,
                     worlds.elapsed_time - start_time, stopped_by, list(features.failures),
                     list(controllers.slow.values()), lines, outcome, error, results)


class _started:
    """Start ``transports`` in order; stop those started, in reverse order, however the block ends."""

    def __init__(self, transports: list[Transport], sim: Simulation) -> None:
        self.transports, self.sim = transports, sim
        self.up: list[Transport] = []

    def __enter__(self) -> None:
        try:
            for t in self.transports:
                t.start(self.sim)
                self.up.append(t)
        except BaseException:
            self.__exit__()
            raise

    def __exit__(self, *exc: object) -> None:
        error: BaseException | None = None
        for t in reversed(self.up):
            try:
                t.stop()
            except BaseException as e:  # the others are still stopped; the first error is raised
                error = error or e
        self.up = []
        if error is not None:
            raise error


def _loop(sim: Simulation, target: int | None, start_step: int, control: RunControl, transports: list[Transport],
          progress: Callable[[Simulation], None] | None, progress_every: float,
          gate: StartGate | None = None) -> float:
    """Step until ``target`` steps or a stop request; the wall-clock time the stepping took [s]."""
    wall0 = _time.perf_counter()
    pace_time, pace_wall = sim.time, wall0  # real-time pacing reference, moved on while paused
    realtime_factor = control.realtime_factor
    next_progress = wall0 + progress_every
    transport = transports[0] if transports else None
    others = transports[1:]
    while not control.stopping and (target is None or sim.worlds.elapsed_steps - start_step < target):
        if transport is not None:
            transport.service(0.01 if control.idle or not sim.worlds.loaded else 0.0)
            for other in others:
                other.service(0.0)
            if gate is not None and gate.active:
                gate.poll(control, transport)
        if control.realtime_factor != realtime_factor:  # a viewer changed the pace: no catching up
            realtime_factor = control.realtime_factor
            pace_time, pace_wall = sim.time, _time.perf_counter()
        if not sim.worlds.loaded:  # unloaded through the transport: wait for a world (the transport loads one)
            control.hold()
            if transport is None:
                break
            continue
        if not control.take_step():  # paused, nothing pending
            if transport is None:
                break  # nothing can ever resume us
            sim.cameras.settle()  # idle: the images of the last steps are published now, not at the next step
            pace_time, pace_wall = sim.time, _time.perf_counter()  # no catching up after a pause
            continue
        if transport is None and realtime_factor is None and not control.paused:
            # nobody outside can act between steps: take up to a batch at once (the step loop lets the backend take
            # the steps after which nothing is due in one call), ending after a step at which a stop was asked
            left = BATCH_STEPS if target is None else target - (sim.worlds.elapsed_steps - start_step)
            sim.step(max(1, min(left, BATCH_STEPS)), until_stop=True)
        else:
            sim.step()
        now = _time.perf_counter()
        if realtime_factor is not None:
            ahead = (sim.time - pace_time) / realtime_factor - (now - pace_wall)
            if ahead > 0.001:
                _time.sleep(ahead)
        if progress is not None and now >= next_progress:
            next_progress = now + progress_every
            progress(sim)
    return _time.perf_counter() - wall0
