"""``sigcore run``: a world run headless, paced, with what starts beside it (the transport, ``--wait-for``'s start
gate, the viewer, the video, the recording) and the report printed at its end (``--results`` as JSON)."""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from .. import __version__, plugins
from ..errors import BudgetError
from ..isolation import CALLBACK_BUDGET, CallbackBudget
from . import linger
from .common import (
    Controllers,
    Seed,
    ViewerHost,
    ViewerPort,
    ViewerRate,
    WorldPath,
    build_sim,
    check_backend,
    draw_world,
    err,
    fail,
    out,
    parse_seed,
    read_world,
)
from .transport import DEFAULT_TRANSPORT, check_endpoints, configure_transport, pick_transport

if TYPE_CHECKING:
    from ..record import Recorder
    from ..sim import Simulation
    from ..sim.startgate import StartGate
    from ..sim.video import VideoRecorder
    from ..transport import Transport
    from ..viewer import Viewer


def _gate(waits: list[str] | None, timeout: float, paused: bool, transport: Transport | None,
          sim: Simulation | None = None) -> StartGate | None:
    """The start gate of ``--wait-for`` (None without it); refuses (exit 2) a malformed or unknown topic, and
    ``--wait-for`` without a transport or with ``--paused``."""
    from ..sim.startgate import StartGate, WaitFor

    if not waits:
        if timeout:
            raise fail(["--wait-timeout needs --wait-for TOPIC (the topics to wait for)"])
        return None
    if paused:
        raise fail(["--paused and --wait-for exclude each other: --paused waits for a client to set PLAYING, "
                    "--wait-for plays by itself once the topics have their peers"])
    if transport is None:
        raise fail(["--wait-for needs a transport (its topics' peers are counted); drop --transport none"])
    from ..transport import Transport

    if type(transport).matched is Transport.matched:  # the base refuses: say so now, not after the start
        raise fail([f"--wait-for: transport '{transport.name}' does not support counting the peers of a topic"])
    parsed = []
    for text in waits:
        try:
            parsed.append(WaitFor.parse(text))
        except ValueError as e:
            raise fail([f"--wait-for {e}"]) from None
    if sim is not None:
        from difflib import get_close_matches

        topics = sorted({e.full_name for e in transport.plan(sim) if e.kind == "topic"})
        for w in parsed:
            if w.topic not in topics:
                close = get_close_matches(w.topic, topics, n=4, cutoff=0.5)
                few = close or [t for t in topics if t.count("/") > 1 or "_" not in t][:6]  # not <agent>_<suffix>
                raise fail([f"--wait-for {w.topic}: not a topic of this simulation's transport "
                            f"'{transport.name}'; valid: e.g. {', '.join(few)} ({len(topics)} topics; "
                            f"sigcore api {sim.world.source} --all lists them)"])
    return StartGate(parsed, timeout, say=lambda line: err.print(line, markup=False, soft_wrap=True))


def _check_pace(fast: bool, realtime: bool, factor: float | None) -> None:
    """Refuse more than one of the pace options."""
    given = [opt for opt, on in (("--fast", fast), ("--realtime", realtime), ("--factor", factor is not None)) if on]
    if len(given) > 1:
        raise fail([f"{' and '.join(given)} exclude each other: choose one pace: --fast (as fast as possible), "
                    "--realtime (= --factor 1) or --factor F (F times real time)"])


def _video(sim: Simulation, path: Path | None, camera: str, fps: float) -> VideoRecorder | None:
    """The recorder of ``--video`` (its encoder started), or None."""
    if path is None:
        return None
    from ..sim.exceptions import VideoError
    from ..sim.video import VideoRecorder

    try:
        return VideoRecorder(sim, path, camera, fps)
    except VideoError as e:
        raise fail([str(e)]) from None


def _record(sim: Simulation, path: Path | None, topics: list[str] | None, rate: float,
            overwrite: bool) -> Recorder | None:
    """The recorder of ``--record`` (its bag open, connected to the simulation), or None."""
    if path is None:
        if topics or overwrite:
            raise fail([f"{'--record-topics' if topics else '--overwrite'} is for --record DIR, which is not given"])
        return None
    from ..record import Recorder, RecordError

    try:
        return Recorder(sim, path, topics, rate, overwrite)
    except RecordError as e:
        raise fail([f"--record: {e}"]) from None


def start_viewer(enabled: bool, host: str, port: int | None, rate: float) -> Viewer | None:
    """The viewer to start beside the transport (``--viewer``), listening already (its URL known), or None."""
    from ..errors import ViewerError
    from ..viewer import DEFAULT_VIEWER

    if not enabled:
        return None
    try:
        cls = plugins.get_viewer(DEFAULT_VIEWER)
    except plugins.PluginError as e:
        raise fail([f"--viewer: {e}; the web viewer is the distribution sigcore-viewer "
                    "(pip install -e plugins/viewer, which scripts/setup.sh does)"]) from None
    try:
        viewer = cls(host=host, port=port, rate=rate)
        viewer.open()
    except ViewerError as e:
        raise fail([f"--viewer: {e}"]) from None
    return viewer


def _pace(fast: bool, realtime: bool, factor: float | None, transport_on: bool) -> float | None:
    """The real-time factor of the run (None: as fast as possible): the option given, else real time with a
    transport or a viewer and as fast as possible without."""
    if fast:
        return None
    if realtime:
        return 1.0
    if factor is not None:
        return factor
    return 1.0 if transport_on else None


def run(
    world_file: WorldPath,
    backend: Annotated[str, typer.Option(help="physics backend", callback=check_backend)] = "mujoco",
    duration: Annotated[float | None, typer.Option(min=0, help="simulated seconds to run [s]")] = None,
    steps: Annotated[int | None, typer.Option(min=0, help="number of steps to run (wins over --duration)")] = None,
    fast: Annotated[bool, typer.Option(
        "--fast", help="as fast as possible (the default without a transport)")] = False,
    realtime: Annotated[bool, typer.Option(
        "--realtime", help="pace at real time, = --factor 1 (the default with a transport)")] = False,
    factor: Annotated[float | None, typer.Option(min=0.001, help="pace at this multiple of real time")] = None,
    paused: Annotated[bool, typer.Option("--paused", help="start paused (resume through a transport)")] = False,
    wait_for: Annotated[list[str] | None, typer.Option(
        "--wait-for", metavar="TOPIC[=N]", help="start paused at t = 0 and play once TOPIC has N (1) matched "
        "subscribers (a topic the simulation publishes) or publishers (one it subscribes to); repeatable")] = None,
    wait_timeout: Annotated[float, typer.Option(
        min=0, help="with --wait-for: play anyway after this long, with a warning [s of wall time]; 0: wait "
        "forever")] = 0.0,
    transport: Annotated[str | None, typer.Option(
        help=f"transport plugin; default '{DEFAULT_TRANSPORT}' when installed; 'none' for a bare batch run")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="no progress display")] = False,
    controller: Controllers = None,
    callback_budget: Annotated[float, typer.Option(
        min=0, help="wall-clock time one controller callback may take before it is reported [s]; 0: no limit")]
        = CALLBACK_BUDGET,
    disable_slow_controllers: Annotated[bool, typer.Option(
        "--disable-slow-controllers", help="disable a controller whose callback took longer than "
        "--callback-budget (after it returned), as if it had raised")] = False,
    worlds: Annotated[list[Path] | None, typer.Option(
        "--worlds", metavar="PATH", help="a world file, or a folder of them, that a client may load while running "
        "(get_available_worlds lists it with worlds/); repeatable")] = None,
    viewer: Annotated[bool, typer.Option(
        "--viewer", help="also start the web viewer (sigcore-viewer): open the printed URL in a browser")] = False,
    viewer_host: ViewerHost = "127.0.0.1",
    viewer_port: ViewerPort = None,
    viewer_rate: ViewerRate = 30.0,
    viewer_linger: Annotated[float | None, typer.Option(
        "--viewer-linger", min=0, metavar="S", help="after the run, keep the viewer's page up (its last moment, the "
        "result, the score table) at most S seconds, or until Enter, the page closed or Ctrl-C; default: until then "
        "with a terminal, not at all without one; 0: never")] = None,
    video: Annotated[Path | None, typer.Option(
        "--video", metavar="OUT.mp4", help="render the run into an MP4 at the simulated pace (time and score in a "
        "corner)")] = None,
    video_camera: Annotated[str, typer.Option(
        "--video-camera", metavar="NAME", help="the video's view: 'overview' (the whole room) or a robot's camera "
        "(NAME or ROBOT/NAME)")] = "overview",
    video_fps: Annotated[float, typer.Option("--video-fps", help="video frames per simulated second [Hz]")] = 30.0,
    record: Annotated[Path | None, typer.Option(
        "--record", metavar="DIR", help="record the run into a rosbag2 directory (MCAP): every topic, the ground "
        "truth, the world file (see docs/recording.md)")] = None,
    record_topics: Annotated[list[str] | None, typer.Option(
        "--record-topics", metavar="REGEX", help="with --record: only the topics a regular expression matches "
        "(re.search on the full name); repeatable")] = None,
    ground_truth_rate: Annotated[float, typer.Option(
        "--ground-truth-rate", min=0, help="with --record: rate of /sigcore/ground_truth [Hz of simulated time]; "
        "0: at the start and the end only")] = 30.0,
    overwrite: Annotated[bool, typer.Option(
        "--overwrite", help="with --record: replace the recording in DIR if it exists")] = False,
    seed: Seed = None,
    results: Annotated[Path | None, typer.Option(
        "--results", metavar="FILE", help="write the run's results as JSON to FILE at its end (also when stopped by "
        "a signal): figures, how it ended, the verdict, each feature's results (the referee's events)")] = None,
) -> None:
    """Run a world headless and print what ran. With a transport (ROS 2 by default) it runs at real time until
    stopped; Ctrl-C (SIGINT) or SIGTERM end it like a QUITTING request, with the results printed. Arguments after
    --ros-args (up to an optional --) go to the transport: -r FROM:=TO, -r __ns:=/NS, -p NAME:=VALUE,
    --log-level LEVEL. --viewer shows the world live in a browser, with play, pause, step, reset and messages.
    --seed N draws the world's <randomize> (the same N, the same world) and seeds the sensor noise."""
    from ..sim import run as run_sim

    seed_value = parse_seed(seed)
    _check_pace(fast, realtime, factor)
    if results is not None and not (results.parent.is_dir() and not results.is_dir()):
        raise fail([f"--results {results}: {'a folder' if results.is_dir() else 'its folder does not exist'}; valid: "
                    "a file in an existing folder"])
    if paused and transport == "none" and not viewer:
        raise fail(["--paused needs a transport or a viewer that can resume the simulation; drop --transport "
                    "none or add --viewer"])
    transport_obj = pick_transport(transport)
    configure_transport(transport_obj, transport)
    _gate(wait_for, wait_timeout, paused, transport_obj)  # the options alone, before the world is built
    if paused and transport_obj is None and not viewer:
        raise fail([f"--paused needs a transport that can resume the simulation, and '{DEFAULT_TRANSPORT}' "
                    "cannot start here (see the line above); --viewer can resume it too"])
    interactive = transport_obj is not None or viewer
    rtf = _pace(fast, realtime, factor, interactive)
    if duration is None and steps is None and not interactive:
        duration = 10.0
        err.print("no --duration or --steps: running 10 simulated seconds")
    missing = [str(p) for p in worlds or [] if not p.exists()]
    if missing:
        raise fail([f"--worlds {p}: no such file or folder" for p in missing])
    world = read_world(world_file)
    layout = draw_world(world, seed_value, "running it with the poses as written")
    sim = build_sim(world_file, backend, controller, layout.world if layout is not None else world)
    sim.worlds.sources = list(worlds or [])
    check_endpoints(transport_obj, sim)
    gate = _gate(wait_for, wait_timeout, paused, transport_obj, sim)
    recorder = _video(sim, video, video_camera, video_fps)
    bag = _record(sim, record, record_topics, ground_truth_rate, overwrite)
    viewer_obj = start_viewer(viewer, viewer_host, viewer_port, viewer_rate)  # listening now: a taken port is exit 2
    terminal = linger.has_terminal()
    linger_s = linger.linger_seconds(viewer_linger, terminal)
    if viewer_obj is not None:
        viewer_obj.hold_at_end = linger_s != 0  # its page stays up after the run (linger.py)
    total = steps if steps is not None else (round(duration / sim.dt) if duration is not None else None)
    show_progress = not quiet and total is not None
    t0 = time.perf_counter()
    tty = sys.stderr.isatty()

    def progress(s: Simulation) -> None:
        if not show_progress or total is None or time.perf_counter() - t0 < 2.0:
            return
        done = s.worlds.elapsed_steps
        line = (f"  t = {s.time:8.2f} s  ({100 * done / max(total, 1):5.1f} %, "
                f"{s.worlds.elapsed_time / (time.perf_counter() - t0):.1f}x real time)")
        if tty:
            err.print(line, end="\r")
        else:
            err.print(line)

    def started(s: Simulation) -> None:
        if not interactive:
            return
        pace = "as fast as possible" if rtf is None else f"at {rtf:g}x real time"
        state = ("paused until the --wait-for topics have their peers" if gate is not None and gate.active else
                 "paused" if s.control.paused else f"running {pace}")
        up = [f"transport '{transport_obj.name}'"] if transport_obj is not None else []
        up += [f"viewer at {viewer_obj.url}"] if viewer_obj is not None else []
        err.print(f"ready: {' and '.join(up)} {'are' if len(up) > 1 else 'is'} up, {state}; Ctrl-C or SIGTERM ends "
                  "the run and prints the results", markup=False, soft_wrap=True)

    # the simulation's own control: transports pause, step and stop through it; --wait-for starts paused too
    if paused or gate is not None:
        sim.control.pause()
    try:
        sim.entities.controllers.budget = CallbackBudget(callback_budget, disable_slow_controllers)
    except BudgetError as e:
        raise fail([f"--callback-budget: {e}"]) from None
    drawn = f", drawn with seed {seed_value}" if layout is not None and world.randomize is not None else ""
    out.print(f"sigcore {__version__}: world '{sim.world.name}' ({world_file}{drawn}) on backend '{backend}', "
              f"timestep {sim.dt} s")
    try:
        report = run_sim(sim, duration=duration, steps=steps, realtime_factor=rtf,
                         control=sim.control, transport=[t for t in (transport_obj, viewer_obj) if t is not None],
                         progress=progress,
                         progress_every=2.0 if not tty else 0.25, started=started, gate=gate)
    except KeyboardInterrupt as e:  # a second signal while stopping
        if viewer_obj is not None:
            viewer_obj.close()
        raise fail([f"interrupted{f' ({e})' if str(e) else ''}: no results"], 130) from None
    finally:
        if recorder is not None:
            recorder.close()
        if bag is not None:
            bag.close()
    if tty and show_progress:
        err.print(" " * 70, end="\r")
    for kind in ("robot", "object", "human", "agent"):
        names = report.agents.get(kind, [])
        if names:
            out.print(f"  {kind + 's:':8} {len(names):3d}  {', '.join(names)}")
    out.print(f"  steps:    {report.steps}")
    out.print(f"  simulated: {report.sim_time_run:.3f} s    wall: {report.wall_time:.3f} s    "
              f"real-time factor: {report.real_time_factor:.1f}")
    if report.stopped_by in ("SIGINT", "SIGTERM"):
        out.print(f"  stopped:  by {report.stopped_by} at t = {report.sim_time:.3f} s")
    if report.error is not None:
        out.print(f"  stopped:  by an error at t = {report.sim_time:.3f} s (not in user code: see the log): "
                  f"{report.error}")
    for f in report.failures:
        out.print(f"  controller of '{f.agent}' disabled ({f.callback} at t={f.time:.3f} s): {f.error}")
    for s in report.slow:
        out.print(f"  controller of '{s.agent}' was slow: {s.count} callback(s) over the budget of {s.budget:g} s, "
                  f"the longest {s.longest:.3f} s ({s.callback})")
    for ff in report.feature_failures:
        out.print(f"  {ff.line()}")
    for name, summary in report.summary.items():
        if summary:
            out.print(f"  {name}: {summary}")
    for line in report.report_lines:
        out.print(line)
    if recorder is not None:
        out.print(f"  video:    {recorder.path} ({recorder.frames} frames, {recorder.duration:.2f} s at "
                  f"{recorder.fps:.4g} fps)")
    if bag is not None:
        state = f"stopped early: {bag.bag.failure}" if bag.bag.failure else "complete"
        out.print(f"  recording: {bag.path} ({bag.messages} messages; {state}); sigcore bag info {bag.path}")
    if results is not None:
        _write_results(results, {"world": sim.world.name, "world_file": str(world_file), "backend": backend,
                                 "seed": seed_value, "exit_code": report.exit_code, **report.as_dict()})
        out.print(f"  results:  {results}")
    if viewer_obj is not None and viewer_obj.hold_at_end:
        sys.stdout.flush()
        linger.linger(viewer_obj, report, linger_s, terminal, lambda line: err.print(line, soft_wrap=True))
    if report.exit_code:  # 3: the run could not go on (a transport or a bug); 1: the world's task failed
        raise typer.Exit(report.exit_code)


def _write_results(path: Path, data: dict[str, object]) -> None:
    """``data`` as JSON in ``path``, whole or not at all (written beside it, then renamed)."""
    import json
    import os

    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        tmp.write_text(json.dumps(data, indent=1, default=str) + "\n")
        os.replace(tmp, path)
    except OSError as e:
        tmp.unlink(missing_ok=True)
        err.print(f"--results {path}: cannot write it: {e}", markup=False, soft_wrap=True)
