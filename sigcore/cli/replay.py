"""The commands on recordings made with ``sigcore run --record``: ``replay`` (the run re-simulated from its world and
input log and compared with what was recorded) and ``bag info`` (what a recording holds)."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Annotated

import typer

from .. import __version__
from ..errors import SigcoreError
from .common import err, fail, out
from .transport import pick_transport


def replay(
    path: Annotated[Path, typer.Argument(help="a recording made with sigcore run --record")],
    until: Annotated[int | None, typer.Option(
        "--until", min=0, help="stop at this step and hand the simulation, paused, to live clients (through "
        "--transport)")] = None,
    transport: Annotated[str, typer.Option(
        help="with --until: the transport the clients take over through ('none': only check and stop)")] = "ros2",
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="no progress display")] = False,
) -> None:
    """Re-simulate a recorded run from its world and its input log, with no client attached, and compare every
    recorded ground-truth frame with the replay at its step (bit for bit on MuJoCo; the first difference stops it,
    naming the step, the entity and the difference) and the referee's score, events and result message by message
    (exit 1 when something differs). Every command from outside is
    applied again (API calls, velocities, resets, entity states, spawns, deletes, entity information); a run that
    loaded or unloaded a world is refused before it runs. --until STEP stops there and hands the paused simulation
    to live clients, so a failed episode can be inspected where it went wrong."""
    from ..record.replay import ReplayError, describe_inputs, load_recording, plan_replay
    from ..record.verify import ReplayCheck
    from ..sim import Simulation
    from ..sim import run as run_sim

    try:
        rec = load_recording(path)
        world = rec.world()
        plan = plan_replay(rec, until)
    except ReplayError as e:
        raise fail([f"sigcore replay: {e}"]) from None
    target, final = plan.target, plan.final
    handover = pick_transport(transport) if until is not None else None
    backend = rec.backend
    try:
        sim = Simulation(world, backend, rec.controllers)
    except SigcoreError as e:
        raise fail([f"sigcore replay: cannot build the recorded world on '{backend}': {e}"]) from None
    try:
        plan.check_start(rec, sim)
    except ReplayError as e:
        raise fail([f"sigcore replay: {e}"]) from None
    kinds = ", ".join(f"{n} {k}" for k, n in describe_inputs(rec.inputs).items()) or "none"
    drawn = f", drawn with seed {rec.seed}" if rec.seed is not None and world.randomize is not None else ""
    out.print(f"sigcore {__version__}: replaying {path} (world '{sim.world.name}'{drawn}, backend '{backend}') to "
              f"step {target} of {final}; recorded commands: {kinds}")
    replayer = plan.replayer(rec)
    check = ReplayCheck(rec.truth, rec.topics, target, plan.whole, sim.backend.replay_tolerance, sim.dt)
    check.attach(sim)
    api_log = logging.getLogger("sigcore.api")
    level = api_log.level
    api_log.setLevel(logging.ERROR)  # refusals were logged when the run was recorded: not again for each one
    total = max(1, target - sim.step_count)

    def progress(s: Simulation) -> None:
        if not quiet:
            err.print(f"  step {s.step_count} of {target} ({100 * s.step_count / total:5.1f} %), "
                      f"{replayer.applied} commands applied", markup=False)

    try:
        report = run_sim(sim, steps=target - sim.step_count, transport=[replayer], realtime_factor=None,
                         progress=progress, progress_every=5.0)
    finally:
        api_log.setLevel(level)
        check.finish(sim)
    error = report.error if report.error is not None else replayer.error
    if error is not None:
        raise fail([f"sigcore replay: the replay stopped at step {sim.step_count}: {error}"], 3)
    late = (f" ({replayer.after_end} of them after the last step, where the run applied them as it stopped)"
            if replayer.after_end else "")
    out.print(f"  replayed: {report.steps} steps, {replayer.applied} commands applied (of {len(rec.inputs)} "
              f"recorded){late}, wall {report.wall_time:.2f} s", markup=False)
    lines, reproduced = check.report(sim)
    for line in lines:
        out.print(f"  {line}", markup=False, soft_wrap=True)
    differs = not reproduced
    if until is not None and handover is not None:
        sim.control.pause()

        def started(s: Simulation) -> None:
            err.print(f"ready: replayed to step {s.step_count} (t = {s.time:.3f} s), paused; transport "
                      f"'{handover.name}' is up: clients take over (play, step, inspect); Ctrl-C ends it",
                      markup=False, soft_wrap=True)

        run_sim(sim, transport=[handover], control=sim.control, realtime_factor=1.0, started=started)
    if differs:
        raise typer.Exit(1)


def bag_info_command(
    path: Annotated[Path, typer.Argument(help="a recording: its directory (or one .mcap file)")],
) -> None:
    """Print what a recording holds, like ros2 bag info: topics, types, counts, times (simulated), attachments;
    a recording cut short is read as far as it goes and its problems are listed (exit 1)."""
    from ..record import BagError, bag_info, format_info

    try:
        info = bag_info(path)
    except BagError as e:
        raise fail([f"sigcore bag info: {e}"]) from None
    for line in format_info(info):
        out.print(line)
    if info.problems:
        raise typer.Exit(1)
