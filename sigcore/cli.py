"""The ``sigcore`` command line. It only parses options, calls the library and prints."""

from __future__ import annotations

import logging
import re
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.table import Table
from rich.text import Text

from . import __version__, cli_linger, plugins
from .cli_common import err, out
from .cli_common import fail as _fail
from .errors import BudgetError, SigcoreError
from .isolation import CALLBACK_BUDGET, CallbackBudget
from .world import WorldError, parse_world

if TYPE_CHECKING:
    from .record import Recorder
    from .sim import Simulation
    from .sim.startgate import StartGate
    from .sim.video import VideoRecorder
    from .transport import Transport
    from .viewer import Viewer
    from .world import World
    from .world.randomize import Layout

app = typer.Typer(help="sigcore: drive a physics simulation through ROS 2 topics and services.",
                  no_args_is_help=True, add_completion=False, pretty_exceptions_enable=False,
                  rich_markup_mode=None)  # help text is plain: units such as [s] stay as written
# Markup off: what is printed comes from users (names, errors, features' lines) and is never interpreted.

WorldPath = Annotated[Path, typer.Argument(exists=True, dir_okay=False, readable=True, help="world XML file")]
Controllers = Annotated[list[str] | None, typer.Option(
    help="attach a controller: AGENT=NAME (registered name or package.module:Class); repeatable")]
ViewerHost = Annotated[str, typer.Option(help="address the viewer listens on; 0.0.0.0 for every interface")]
ViewerPort = Annotated[int | None, typer.Option(
    help="the viewer's port; default 8080, or the next free one when it is taken")]
ViewerRate = Annotated[float, typer.Option(help="scene updates per second of wall time [Hz]")]
Seed = Annotated[str | None, typer.Option(
    "--seed", metavar="N", help="draw the world's <randomize> with this seed (the same N, the same world) and use it "
    "as the seed of the sensor noise; an integer >= 0")]

MAX_SEED = 2**64 - 1
"""Largest ``--seed``."""


def _backend_names() -> list[str]:
    return sorted(plugins.backends())


def _check_backend(value: str) -> str:
    names = _backend_names()
    if value not in names:
        raise typer.BadParameter(f"'{value}' is not installed; available: {', '.join(names) or 'none'}")
    return value


def _seed(text: str | None) -> int | None:
    """The value of ``--seed`` (exit 2 unless an integer 0 <= N <= :data:`MAX_SEED`)."""
    if text is None:
        return None
    digits = text.strip()
    if not re.fullmatch(r"[0-9]{1,20}", digits) or int(digits) > MAX_SEED:
        raise _fail([f"--seed {text!r}: not a seed; valid: an integer 0 <= N <= {MAX_SEED} (the same N gives the same "
                     "world)"])
    return int(digits)


def _parse(world_file: Path) -> World:
    """The world file, parsed (exit 2 with its issues)."""
    try:
        return parse_world(world_file)
    except WorldError as e:
        raise _fail([str(i) for i in e.issues]) from None


def _draw(world: World, seed: int | None, unseeded: str) -> Layout | None:
    """``world`` drawn with ``--seed`` (its ``<randomize>``, and the seed of its sensor noise), or None without it;
    says on stderr what the seed does (or, without one, that the poses are the file's: ``unseeded``)."""
    from .world.randomize import draw

    if seed is None:
        if world.randomize is not None:
            err.print(f"{world.source}: <randomize> of {len(world.randomize.entities)} entities: {unseeded}; --seed N "
                      "draws them (the same N, the same world)", markup=False, soft_wrap=True)
        return None
    if world.randomize is None:
        err.print(f"--seed {seed}: {world.source} has no <randomize>: the seed only sets the seed of the sensor noise "
                  "(instead of <world seed>)", markup=False, soft_wrap=True)
    try:
        return draw(world, seed, noise=True)
    except WorldError as e:
        raise _fail([str(i) for i in e.issues]) from None


def _load(world_file: Path, backend: str, controllers: list[str] | None = None, world: World | None = None) \
        -> Simulation:
    """Build the simulation of ``world`` (else of the file as written); every failure is printed as what it is
    (world file, controller, feature, backend)."""
    from .agent.exceptions import ApiError
    from .errors import BackendError
    from .sim import FeatureError, Simulation

    overrides: dict[str, str] = {}
    for item in controllers or []:
        agent, sep, spec = item.partition("=")
        if not sep or not agent or not spec:
            raise _fail([f"--controller wants AGENT=CONTROLLER (e.g. robot_000=cleanup.robot), got {item!r}"])
        overrides[agent] = spec
    if world is None:
        world = _parse(world_file)
    try:
        return Simulation(world, backend, overrides)  # fires sigcore_world_loaded
    except BackendError as e:  # first (a BackendRefusal is an ApiError too); located at the entity it names
        raise _fail([f"{_entity_location(world, str(e))}: cannot build the world with backend '{backend}': {e}"]) \
            from None
    except ApiError as e:
        raise _fail([f"{world_file}: --controller: {e}"]) from None
    except WorldError as e:  # the world file, a controller that cannot be created, a feature's attributes
        raise _fail([str(i) for i in e.issues]) from None
    except FeatureError as e:  # names the feature and its <plugin> line
        raise _fail([str(e)]) from None
    except plugins.PluginError as e:
        raise _fail([f"{world_file}: {e}"]) from None
    except SigcoreError as e:
        raise _fail([f"{world_file}: {e}"]) from None
    except KeyboardInterrupt:
        raise _fail(["interrupted while building the world"], 130) from None
    except (Exception, SystemExit) as e:  # not one of ours: the backend's engine (or a bug) failed
        raise _fail([f"{_entity_location(world, str(e))}: cannot build the world with backend '{backend}': "
                     f"{type(e).__name__}: {e}"]) from None


def _entity_location(world: World, text: str) -> str:
    """``file:line:column`` of the first agent that ``text`` names as ``kind 'name'`` (else of ``<world>``)."""
    for match in re.finditer(r"\b(?:robot|object|human|agent|entity) '([A-Za-z][A-Za-z0-9_]*)'", text):
        line, column = world.location(match.group(1))
        if line:
            return f"{world.source}:{line}:{column}"
    line, column = world.location("")
    return f"{world.source}:{line or 1}:{column or 1}"


def _check_endpoints(transport: Transport | None, sim: Simulation) -> None:
    """Refuse (exit 2) a world whose endpoints ``transport`` cannot create: invalid or twice-used names."""
    from .errors import TransportError

    if transport is None:
        return
    try:
        issues = transport.check(sim)
    except ImportError as e:  # the transport's libraries are missing: it cannot start anyway
        raise _fail([f"--transport {transport.name}: cannot plan its endpoints here ({e})"]) from None
    except TransportError as e:  # its arguments do not fit this world (e.g. -p naming an agent it does not have)
        raise _fail([f"{TRANSPORT_ARGS}: {e}"]) from None
    if issues:
        raise _fail([str(i) for i in issues])


DEFAULT_TRANSPORT = "ros2"
"""The transport ``sigcore run`` starts when none is named and it is installed and can start."""


def _transport(name: str | None) -> Transport | None:
    """The transport to start: ``name``, none for ``"none"``, or the default when it can start (else one line)."""
    if name == "none":
        return None
    if name is None:
        try:
            cls = plugins.get_transport(DEFAULT_TRANSPORT)
        except plugins.PluginError as e:  # not installed, or its plugin failed to load (the message says which)
            err.print(f"{e}: running without a transport (--transport none says so and silences this line)",
                      markup=False, soft_wrap=True)
            return None
        reason = cls.unavailable()
        if reason is not None:
            err.print(f"transport '{DEFAULT_TRANSPORT}' cannot start: {reason}; running without a transport "
                      "(--transport none silences this line)", markup=False, soft_wrap=True)
            return None
        return cls()
    try:
        cls = plugins.get_transport(name)
    except plugins.PluginError as e:
        raise _fail([f"--transport: {e}; or 'none' for a run without a transport"]) from None
    reason = cls.unavailable()
    if reason is not None:
        raise _fail([f"--transport {name}: {reason} (--transport none runs without a transport)"])
    return cls()


TRANSPORT_ARGS = "--ros-args"
"""Everything after this on ``sigcore run``'s command line (up to an optional ``--``) is the transport's."""

_transport_args: list[str] | None = None
"""The arguments after ``--ros-args`` (set by :func:`main`; None: none given)."""


def split_transport_args(argv: list[str]) -> tuple[list[str], list[str] | None]:
    """``argv`` without the transport's arguments, and those arguments: everything after ``--ros-args`` up to an
    optional ``--`` (what follows ``--`` is sigcore's again); None when ``--ros-args`` is absent."""
    if TRANSPORT_ARGS not in argv:
        return argv, None
    i = argv.index(TRANSPORT_ARGS)
    rest = argv[i + 1:]
    end = rest.index("--") if "--" in rest else len(rest)
    return argv[:i] + rest[end + 1:], rest[:end]


def _configure(transport: Transport | None, transport_name: str | None) -> None:
    """Hand the arguments after ``--ros-args`` to the transport (exit 2 if it has none or refuses them)."""
    from .errors import TransportError

    if _transport_args is None:
        return
    if transport is None:
        why = ("--transport none has no transport to take them" if transport_name == "none" else
               f"the default transport '{DEFAULT_TRANSPORT}' cannot start here (see the line above)")
        raise _fail([f"{TRANSPORT_ARGS}: {why}; drop {TRANSPORT_ARGS} or run with a transport"])
    try:
        transport.configure(list(_transport_args))
    except TransportError as e:
        raise _fail([f"{TRANSPORT_ARGS}: {e}"]) from None


def _gate(waits: list[str] | None, timeout: float, paused: bool, transport: Transport | None,
          sim: Simulation | None = None) -> StartGate | None:
    """The start gate of ``--wait-for`` (None without it); refuses (exit 2) a malformed or unknown topic, and
    ``--wait-for`` without a transport or with ``--paused``."""
    from .sim.startgate import StartGate, WaitFor

    if not waits:
        if timeout:
            raise _fail(["--wait-timeout needs --wait-for TOPIC (the topics to wait for)"])
        return None
    if paused:
        raise _fail(["--paused and --wait-for exclude each other: --paused waits for a client to set PLAYING, "
                     "--wait-for plays by itself once the topics have their peers"])
    if transport is None:
        raise _fail(["--wait-for needs a transport (its topics' peers are counted); drop --transport none"])
    from .transport import Transport

    if type(transport).matched is Transport.matched:  # the base refuses: say so now, not after the start
        raise _fail([f"--wait-for: transport '{transport.name}' does not support counting the peers of a topic"])
    parsed = []
    for text in waits:
        try:
            parsed.append(WaitFor.parse(text))
        except ValueError as e:
            raise _fail([f"--wait-for {e}"]) from None
    if sim is not None:
        from difflib import get_close_matches

        topics = sorted({e.full_name for e in transport.plan(sim) if e.kind == "topic"})
        for w in parsed:
            if w.topic not in topics:
                close = get_close_matches(w.topic, topics, n=4, cutoff=0.5)
                few = close or [t for t in topics if t.count("/") > 1 or "_" not in t][:6]  # not <agent>_<suffix>
                raise _fail([f"--wait-for {w.topic}: not a topic of this simulation's transport "
                             f"'{transport.name}'; valid: e.g. {', '.join(few)} ({len(topics)} topics; "
                             f"sigcore api {sim.world.source} --all lists them)"])
    return StartGate(parsed, timeout, say=lambda line: err.print(line, markup=False, soft_wrap=True))


def _check_pace(fast: bool, realtime: bool, factor: float | None) -> None:
    """Refuse more than one of the pace options."""
    given = [opt for opt, on in (("--fast", fast), ("--realtime", realtime), ("--factor", factor is not None)) if on]
    if len(given) > 1:
        raise _fail([f"{' and '.join(given)} exclude each other: choose one pace: --fast (as fast as possible), "
                     "--realtime (= --factor 1) or --factor F (F times real time)"])


def _video(sim: Simulation, path: Path | None, camera: str, fps: float) -> VideoRecorder | None:
    """The recorder of ``--video`` (its encoder started), or None."""
    if path is None:
        return None
    from .sim.exceptions import VideoError
    from .sim.video import VideoRecorder

    try:
        return VideoRecorder(sim, path, camera, fps)
    except VideoError as e:
        raise _fail([str(e)]) from None


def _record(sim: Simulation, path: Path | None, topics: list[str] | None, rate: float,
            overwrite: bool) -> Recorder | None:
    """The recorder of ``--record`` (its bag open, connected to the simulation), or None."""
    if path is None:
        if topics or overwrite:
            raise _fail([f"{'--record-topics' if topics else '--overwrite'} is for --record DIR, which is not given"])
        return None
    from .record import Recorder, RecordError

    try:
        return Recorder(sim, path, topics, rate, overwrite)
    except RecordError as e:
        raise _fail([f"--record: {e}"]) from None


def _viewer(enabled: bool, host: str, port: int | None, rate: float) -> Viewer | None:
    """The viewer to start beside the transport (``--viewer``), listening already (its URL known), or None."""
    from .errors import ViewerError
    from .viewer import DEFAULT_VIEWER

    if not enabled:
        return None
    try:
        cls = plugins.get_viewer(DEFAULT_VIEWER)
    except plugins.PluginError as e:
        raise _fail([f"--viewer: {e}; the web viewer is the distribution sigcore-viewer "
                     "(pip install -e plugins/viewer, which scripts/setup.sh does)"]) from None
    try:
        viewer = cls(host=host, port=port, rate=rate)
        viewer.open()
    except ViewerError as e:
        raise _fail([f"--viewer: {e}"]) from None
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


@app.command()
def run(
    world_file: WorldPath,
    backend: Annotated[str, typer.Option(help="physics backend", callback=_check_backend)] = "mujoco",
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
    from .sim import run as run_sim

    seed_value = _seed(seed)
    _check_pace(fast, realtime, factor)
    if results is not None and not (results.parent.is_dir() and not results.is_dir()):
        raise _fail([f"--results {results}: {'a folder' if results.is_dir() else 'its folder does not exist'}; valid: "
                     "a file in an existing folder"])
    if paused and transport == "none" and not viewer:
        raise _fail(["--paused needs a transport or a viewer that can resume the simulation; drop --transport "
                     "none or add --viewer"])
    transport_obj = _transport(transport)
    _configure(transport_obj, transport)
    _gate(wait_for, wait_timeout, paused, transport_obj)  # the options alone, before the world is built
    if paused and transport_obj is None and not viewer:
        raise _fail([f"--paused needs a transport that can resume the simulation, and '{DEFAULT_TRANSPORT}' "
                     "cannot start here (see the line above); --viewer can resume it too"])
    interactive = transport_obj is not None or viewer
    rtf = _pace(fast, realtime, factor, interactive)
    if duration is None and steps is None and not interactive:
        duration = 10.0
        err.print("no --duration or --steps: running 10 simulated seconds")
    missing = [str(p) for p in worlds or [] if not p.exists()]
    if missing:
        raise _fail([f"--worlds {p}: no such file or folder" for p in missing])
    world = _parse(world_file)
    layout = _draw(world, seed_value, "running it with the poses as written")
    sim = _load(world_file, backend, controller, layout.world if layout is not None else world)
    sim.worlds.sources = list(worlds or [])
    _check_endpoints(transport_obj, sim)
    gate = _gate(wait_for, wait_timeout, paused, transport_obj, sim)
    recorder = _video(sim, video, video_camera, video_fps)
    bag = _record(sim, record, record_topics, ground_truth_rate, overwrite)
    viewer_obj = _viewer(viewer, viewer_host, viewer_port, viewer_rate)  # listening now: a taken port is exit 2
    terminal = cli_linger.has_terminal()
    linger_s = cli_linger.linger_seconds(viewer_linger, terminal)
    if viewer_obj is not None:
        viewer_obj.hold_at_end = linger_s != 0  # its page stays up after the run (cli_linger)
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
        raise _fail([f"--callback-budget: {e}"]) from None
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
        raise _fail([f"interrupted{f' ({e})' if str(e) else ''}: no results"], 130) from None
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
        cli_linger.linger(viewer_obj, report, linger_s, terminal, lambda line: err.print(line, soft_wrap=True))
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


@app.command()
def view(
    world_file: Annotated[Path, typer.Argument(
        exists=True, help="world XML file, or a recording: a directory made by sigcore run --record (or its .mcap)")],
    backend: Annotated[str, typer.Option(help="physics backend", callback=_check_backend)] = "mujoco",
    transport: Annotated[str | None, typer.Option(
        help=f"transport plugin; default '{DEFAULT_TRANSPORT}' when installed; 'none': the viewer alone")] = None,
    controller: Controllers = None,
    viewer_host: ViewerHost = "127.0.0.1",
    viewer_port: ViewerPort = None,
    viewer_rate: ViewerRate = 30.0,
    seed: Seed = None,
) -> None:
    """Open a world in the web viewer, paused at t = 0: press play in the browser (= sigcore run WORLD --viewer
    --paused). The transport (ROS 2 by default) runs beside it; Ctrl-C ends the run and prints the results.
    Given a recording (sigcore run --record DIR), the viewer plays it back with a timeline to scrub (with the seed
    the run was drawn with)."""
    if world_file.is_dir() or world_file.suffix == ".mcap":
        if seed is not None:
            raise _fail(["--seed is for a world file: a recording is shown with the seed it was recorded with"])
        _view_recording(world_file, viewer_host, viewer_port, viewer_rate)
        return
    run(world_file, backend=backend, duration=None, steps=None, fast=False, realtime=False, factor=None,
        paused=True, wait_for=None, wait_timeout=0.0, transport=transport, quiet=True, controller=controller,
        callback_budget=CALLBACK_BUDGET, disable_slow_controllers=False, worlds=None, viewer=True,
        viewer_host=viewer_host, viewer_port=viewer_port, viewer_rate=viewer_rate, seed=seed)


def _view_recording(path: Path, host: str, port: int | None, rate: float) -> None:
    """``sigcore view DIR``: check the recording, open the viewer, play it back until Ctrl-C."""
    import signal

    from .errors import ViewerError
    from .record import BagError, bag_info

    try:
        info = bag_info(path)
    except BagError as e:
        raise _fail([f"sigcore view: {e}"]) from None
    for problem in info.problems:
        err.print(f"sigcore view: warning: {problem}; showing what is readable")
    viewer = _viewer(True, host, port, rate)
    assert viewer is not None
    stop = {"now": False}

    def interrupted(*_: object) -> None:
        stop["now"] = True

    previous = {sig: signal.signal(sig, interrupted) for sig in (signal.SIGINT, signal.SIGTERM)}
    err.print(f"ready: viewer at {viewer.url} shows {path} ({(info.end_ns - info.start_ns) / 1e9:.2f} s recorded); "
              "Ctrl-C ends it", markup=False, soft_wrap=True)
    try:
        viewer.play_recording(path, lambda: stop["now"])
    except ViewerError as e:
        raise _fail([f"sigcore view: {e}"]) from None
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        viewer.stop()


@app.command()
def check(
    world_file: WorldPath,
    backend: Annotated[str, typer.Option(help="backend to build it with", callback=_check_backend)] = "mujoco",
    transport: Annotated[str | None, typer.Option(
        help=f"transport whose endpoints to check; default '{DEFAULT_TRANSPORT}' when it can start; 'none'")] = None,
    seed: Seed = None,
) -> None:
    """Validate a world file: syntax, references, controllers, plugins, that the backend builds it, and that the
    transport can create every endpoint (valid ROS names, none used twice). --seed N checks the world its
    <randomize> draws with N and prints what was drawn: each entity's x y z [m] and yaw [rad], each option picked."""
    seed_value = _seed(seed)
    transport_obj = _transport(transport)
    world = _parse(world_file)
    layout = _draw(world, seed_value, "checked with the poses as written")
    if layout is not None and world.randomize is not None:
        out.print(f"{world_file}: seed {layout.seed} draws")
        for pick in layout.picks:
            choice = next(c for c in world.randomize.choices if c.entity == pick.entity)
            out.print(f"  {pick.entity:<16} option {pick.option + 1} of {len(choice.options)} (line {pick.line})")
        for p in layout.placements:
            x, y, z = (v + 0.0 for v in p.xyz)
            on = f"  on {p.surface}" if p.surface is not None else ""
            out.print(f"  {p.entity:<16} x {x:10.6f}  y {y:10.6f}  z {z:9.6f}  yaw {p.rpy[2] + 0.0:9.6f}{on}")
    sim = _load(world_file, backend, world=layout.world if layout is not None else world)
    _check_endpoints(transport_obj, sim)
    with_transport = f", endpoints of '{transport_obj.name}' checked" if transport_obj is not None else ""
    out.print(f"{world_file}: ok ({len(sim.entities)} agents, built with '{backend}'{with_transport})")


@app.command()
def api(
    world_file: Annotated[Path | None, typer.Argument(exists=True, dir_okay=False, help="world XML file")] = None,
    markdown: Annotated[bool, typer.Option("--markdown", help="print the reference as Markdown")] = False,
    backend: Annotated[str, typer.Option(help="physics backend", callback=_check_backend)] = "mujoco",
    transport: Annotated[str, typer.Option(help="the transport whose endpoints to list, or 'none'")] = "ros2",
    every: Annotated[bool, typer.Option("--all", help="also print each agent's endpoints one per line")] = False,
) -> None:
    """Print every endpoint a run of a world will have: the agents' API (with the features'), the publications
    of the core and the features, and the transport's own topics and services."""
    from .api.docs import api_markdown

    if markdown:
        print(api_markdown())
        return
    if world_file is None:
        raise _fail(["give a world file (or --markdown for the reference)"])
    sim = _load(world_file, backend)
    entries = sim.api_entries()
    agent_topics = {p.topic for p in sim.publications.declared if p.agent}
    described: dict[str, str] = {}
    if transport != "none":
        try:
            described = plugins.get_transport(transport)().describe(sim)
        except plugins.PluginError as e:
            raise _fail([str(e)]) from None
        except ImportError as e:
            err.print(f"transport '{transport}' cannot describe its endpoints here ({e}); listing the core's",
                      markup=False)
    per_agent: dict[str, str] = {}
    print("agent API (one endpoint per agent of the listed kinds: <agent><suffix>; in parentheses, how many agents "
          "have it" + (f" with transport '{transport}'" if described else "") + ")")
    print(f"  {'suffix':<34} {'direction':<9} {'type':<28} {'from':<8} kinds: request -> response")
    for entry in entries:
        req = ", ".join(entry.request.model_fields) if entry.request else entry.ros_type
        res = ", ".join(entry.response.model_fields) if entry.response else ""
        # the transport may leave some agents' endpoints out (ROS 2: sigros_agents)
        agents = [a for a, h in sim.entities.items() if h.kind in entry.kinds and (
            entry.direction != "publish" or entry.name_for(a) in agent_topics)
            and (not described or entry.name_for(a) in described)]
        for agent in agents:
            per_agent[entry.name_for(agent)] = entry.ros_type
        print(f"  {entry.suffix:<34} {entry.direction:<9} {entry.ros_type:<28} {entry.origin:<8} "
              f"{','.join(sorted(entry.kinds))} ({len(agents)}): {req}" + (f" -> {res}" if res else ""))
    others = {p.topic: (p.full_type, f"{p.qos}, from {p.origin}") for p in sim.publications.declared
              if not p.agent}
    for name, kind in described.items():
        if name not in per_agent and name not in others:
            others[name] = (kind, f"transport {transport}")
    print("\nother topics and services")
    for name in sorted(others):
        kind, what = others[name]
        print(f"  {name:<40} {kind:<45} {what}")
    by_agent = {a: sum(1 for n in per_agent if n.startswith(a) and n[len(a):len(a) + 1] == "_") for a in sim.entities}
    print()
    for agent, handle in sim.entities.items():
        print(f"  {agent} ({handle.kind}): {by_agent[agent]} endpoints")
    if every:
        print("\nevery agent endpoint")
        for name in sorted(per_agent):
            print(f"  {name:<50} {per_agent[name]}")
    print(f"{len(sim.entities)} agents, {len(per_agent)} agent endpoints, {len(others)} others, "
          f"{len(per_agent) + len(others)} in all")


@app.command()
def interfaces(
    out_dir: Annotated[Path, typer.Option("--out", help="interface package directory")] = Path(
        "interfaces/sigcore_msgs"),
) -> None:
    """Write the sigcore_msgs ROS 2 interface files (msg/, srv/) generated from the API table."""
    from .api.interfaces import write_interfaces

    files = write_interfaces(out_dir)
    out.print(f"{len(files)} interface files in {out_dir}")


@app.command(name="plugins")
def plugins_cmd() -> None:
    """List installed plugins, their distributions and versions, and what each provides."""
    infos = plugins.plugin_infos()
    table = Table(title="sigcore plugins (entry-point group 'sigcore')")
    for col in ("plugin", "distribution", "version", "provides"):
        table.add_column(col)
    for info in infos:  # cells as Text: a plugin's names and errors are never read as markup
        status = ", ".join(info.provided()) or "-" if info.loaded else f"FAILED: {info.error}"
        table.add_row(*(Text(cell) for cell in (info.name, info.distribution, info.version, status)))
    out.print(table)
    if not infos:
        out.print("no plugins installed (pip install sigcore-backend-mujoco)")


@app.command(name="spawnables")
def spawnables_cmd(
    world_file: Annotated[Path | None, typer.Argument(exists=True, dir_okay=False, help="world XML file (its "
                                                       "models/ folder counts too)")] = None,
) -> None:
    """List the models a spawn request may name as model://NAME: name, origin, description."""
    from .world.models import World
    from .world.spawnables import find_spawnables

    try:
        world = parse_world(world_file) if world_file is not None else World()
    except WorldError as e:
        raise _fail([str(i) for i in e.issues]) from None
    found = find_spawnables(world, plugins.spawnables().values())
    table = Table(title="spawnables (model://NAME)")
    for col in ("name", "origin", "description"):
        table.add_column(col)
    for s in found:  # cells as Text: names and descriptions are never read as markup
        table.add_row(Text(s.name), Text(s.origin), Text(s.description))
    out.print(table)
    if not found:
        out.print("no spawnables (folders of worlds/models with a spawnable.xml, or a plugin's)")


@app.command(name="worlds")
def worlds_cmd(
    paths: Annotated[list[Path] | None, typer.Argument(help="world files or folders to list besides worlds/ and the "
                                                      "plugins' (as sigcore run --worlds adds them)")] = None,
) -> None:
    """List the worlds a running simulation may load (load_world): name, file, where found, tags, description."""
    from .world.catalogue import default_sources, find_worlds

    found, problems = find_worlds(default_sources([], list(paths or []), plugins.worlds()))
    table = Table(title="worlds (load_world uri: a name, path or file:// URI)")
    for col in ("name", "file", "source", "tags", "description"):
        table.add_column(col)
    for w in found:  # cells as Text: names and descriptions are never read as markup
        table.add_row(Text(w.name), Text(str(w.path)), Text(w.source), Text(" ".join(w.tags)), Text(w.description))
    out.print(table)
    for problem in problems:
        err.print(problem, markup=False, soft_wrap=True)
    if problems:
        raise typer.Exit(2)


def _eval_command() -> None:
    from .cli_eval import eval_command

    app.command(name="eval")(eval_command)


_eval_command()


@app.command()
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
    from .record.replay import ReplayError, describe_inputs, load_recording, plan_replay
    from .record.verify import ReplayCheck
    from .sim import Simulation
    from .sim import run as run_sim

    try:
        rec = load_recording(path)
        world = rec.world()
        plan = plan_replay(rec, until)
    except ReplayError as e:
        raise _fail([f"sigcore replay: {e}"]) from None
    target, final = plan.target, plan.final
    handover = _transport(transport) if until is not None else None
    backend = rec.backend
    try:
        sim = Simulation(world, backend, rec.controllers)
    except SigcoreError as e:
        raise _fail([f"sigcore replay: cannot build the recorded world on '{backend}': {e}"]) from None
    try:
        plan.check_start(rec, sim)
    except ReplayError as e:
        raise _fail([f"sigcore replay: {e}"]) from None
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
        raise _fail([f"sigcore replay: the replay stopped at step {sim.step_count}: {error}"], 3)
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


bag_app = typer.Typer(help="Recordings (rosbag2 directories with MCAP storage): look inside, play back.",
                      no_args_is_help=True, rich_markup_mode=None)
app.add_typer(bag_app, name="bag")


@bag_app.command(name="info")
def bag_info_command(
    path: Annotated[Path, typer.Argument(help="a recording: its directory (or one .mcap file)")],
) -> None:
    """Print what a recording holds, like ros2 bag info: topics, types, counts, times (simulated), attachments;
    a recording cut short is read as far as it goes and its problems are listed (exit 1)."""
    from .record import BagError, bag_info, format_info

    try:
        info = bag_info(path)
    except BagError as e:
        raise _fail([f"sigcore bag info: {e}"]) from None
    for line in format_info(info):
        out.print(line)
    if info.problems:
        raise typer.Exit(1)


def main() -> None:
    """Console-script entry point. Arguments after ``--ros-args`` (up to an optional ``--``) are the transport's
    (``sigcore run`` only), taken out before typer parses the rest."""
    global _transport_args
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    argv, _transport_args = split_transport_args(sys.argv[1:])
    if _transport_args is not None and (not argv or argv[0] != "run"):
        err.print(f"{TRANSPORT_ARGS} is taken by 'sigcore run' only (sigcore run WORLD [OPTIONS] {TRANSPORT_ARGS} "
                  "-r FROM:=TO -p NAME:=VALUE ...)", markup=False, soft_wrap=True)
        raise SystemExit(2)
    plugins.load_plugins()
    plugins.add_commands(app)
    app(args=argv)
