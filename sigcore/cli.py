"""The ``sigcore`` command line. It only parses options, calls the library and prints."""

from __future__ import annotations

import logging
import sys
import time
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

from . import __version__, plugins
from .world import WorldError, parse_world

app = typer.Typer(help="sigcore: drive a physics simulation through ROS 2 topics and services.",
                  no_args_is_help=True, add_completion=False, pretty_exceptions_enable=False)
out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False)

WorldPath = Annotated[Path, typer.Argument(exists=True, dir_okay=False, readable=True, help="world XML file")]


def _fail(lines: list[str], code: int = 2) -> typer.Exit:
    for line in lines:
        err.print(line, markup=False, soft_wrap=True)
    return typer.Exit(code)


def _backend_names() -> list[str]:
    return sorted(plugins.backends())


def _check_backend(value: str) -> str:
    names = _backend_names()
    if value not in names:
        raise typer.BadParameter(f"'{value}' is not installed; available: {', '.join(names) or 'none'}")
    return value


def _load(world_file: Path, backend: str, controllers: list[str] | None = None) -> object:
    from .agent.exceptions import ApiError
    from .sim import Simulation

    overrides: dict[str, str] = {}
    for item in controllers or []:
        agent, sep, spec = item.partition("=")
        if not sep or not agent or not spec:
            raise _fail([f"--controller wants AGENT=CONTROLLER (e.g. robot_000=cleanup.robot), got {item!r}"])
        overrides[agent] = spec
    try:
        world = parse_world(world_file)
        plugins.notify("sigcore_world_loaded", world=world)
        return Simulation(world, backend, overrides)
    except ApiError as e:
        raise _fail([f"{world_file}: --controller: {e}"]) from None
    except WorldError as e:
        raise _fail([str(i) for i in e.issues]) from None
    except plugins.PluginError as e:
        raise _fail([f"{world_file}: {e}"]) from None
    except Exception as e:  # a backend that cannot build the world
        raise _fail([f"{world_file}: cannot build the world with backend '{backend}': {e}"]) from None


@app.command()
def run(
    world_file: WorldPath,
    backend: Annotated[str, typer.Option(help="physics backend", callback=_check_backend)] = "mujoco",
    duration: Annotated[float | None, typer.Option(min=0, help="simulated seconds to run [s]")] = None,
    steps: Annotated[int | None, typer.Option(min=0, help="number of steps to run (wins over --duration)")] = None,
    realtime: Annotated[bool, typer.Option("--realtime", help="pace the simulation at real time")] = False,
    factor: Annotated[float | None, typer.Option(min=0.001, help="pace at this multiple of real time")] = None,
    paused: Annotated[bool, typer.Option("--paused", help="start paused (resume through a transport)")] = False,
    transport: Annotated[str | None, typer.Option(help="transport plugin, e.g. ros2")] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="no progress display")] = False,
    controller: Annotated[list[str] | None, typer.Option(
        help="attach a controller: AGENT=NAME (registered name or package.module:Class); repeatable")] = None,
) -> None:
    """Run a world headless and print what ran."""
    from .sim import run as run_sim

    if realtime and factor is not None:
        raise _fail(["--realtime and --factor exclude each other: --realtime is --factor 1"])
    if paused and transport is None:
        raise _fail(["--paused needs a transport that can resume the simulation, e.g. --transport ros2"])
    if duration is None and steps is None and transport is None:
        duration = 10.0
        err.print("no --duration or --steps: running 10 simulated seconds")
    transport_obj = None
    if transport is not None:
        try:
            transport_obj = plugins.get_transport(transport)()
        except plugins.PluginError as e:
            raise _fail([str(e)]) from None
    sim = _load(world_file, backend, controller)
    from .sim import Simulation

    assert isinstance(sim, Simulation)
    total = steps if steps is not None else (round(duration / sim.dt) if duration is not None else None)
    show_progress = not quiet and total is not None
    started = time.perf_counter()
    tty = sys.stderr.isatty()

    def progress(s: Simulation) -> None:
        if not show_progress or total is None or time.perf_counter() - started < 2.0:
            return
        done = s.step_count
        line = (f"  t = {s.time:8.2f} s  ({100 * done / max(total, 1):5.1f} %, "
                f"{s.time / (time.perf_counter() - started):.1f}x real time)")
        if tty:
            err.print(line, end="\r")
        else:
            err.print(line)

    rtf = 1.0 if realtime else factor
    sim.control.paused = paused  # the simulation's own control: transports pause, step and stop through it
    out.print(f"sigcore {__version__}: world '{sim.world.name}' ({world_file}) on backend '{backend}', "
              f"timestep {sim.dt} s")
    try:
        report = run_sim(sim, duration=duration, steps=steps, realtime_factor=rtf,
                         control=sim.control, transport=transport_obj, progress=progress,
                         progress_every=2.0 if not tty else 0.25)
    except KeyboardInterrupt:
        raise _fail(["interrupted"], 130) from None
    if tty and show_progress:
        err.print(" " * 70, end="\r")
    for kind in ("robot", "object", "human", "agent"):
        names = report.agents.get(kind, [])
        if names:
            out.print(f"  {kind + 's:':8} {len(names):3d}  {', '.join(names)}")
    out.print(f"  steps:    {report.steps}")
    out.print(f"  simulated: {report.sim_time_run:.3f} s    wall: {report.wall_time:.3f} s    "
              f"real-time factor: {report.real_time_factor:.1f}")
    for f in report.failures:
        out.print(f"  controller of '{f.agent}' disabled ({f.callback} at t={f.time:.3f} s): {f.error}")
    for name, summary in report.summary.items():
        if summary:
            out.print(f"  {name}: {summary}")
    for feature in sim.features.values():
        for line in feature.report():
            out.print(line, markup=False, highlight=False)
    if any(feature.outcome() is False for feature in sim.features.values()):
        raise typer.Exit(1)  # the world's task failed (e.g. the referee's result is not 'succeeded')


@app.command()
def check(
    world_file: WorldPath,
    backend: Annotated[str, typer.Option(help="backend to build it with", callback=_check_backend)] = "mujoco",
) -> None:
    """Validate a world file: syntax, references, controllers, plugins, and that the backend builds it."""
    sim = _load(world_file, backend)
    from .sim import Simulation

    assert isinstance(sim, Simulation)
    out.print(f"{world_file}: ok ({len(sim.agents)} agents, built with '{backend}')")


@app.command()
def api(
    world_file: Annotated[Path | None, typer.Argument(exists=True, dir_okay=False, help="world XML file")] = None,
    markdown: Annotated[bool, typer.Option("--markdown", help="print the reference as Markdown")] = False,
) -> None:
    """Print the API table: every topic and service of every agent of a world."""
    from .api import api_table, entries_for

    if markdown:
        from .api.docs import api_markdown

        print(api_markdown())
        return
    if world_file is None:
        raise _fail(["give a world file (or --markdown for the reference)"])
    try:
        world = parse_world(world_file)
    except WorldError as e:
        raise _fail([str(i) for i in e.issues]) from None
    table = Table(title="agent API (one endpoint per agent of the listed kinds: <agent><suffix>)")
    for col in ("suffix", "direction", "type", "request -> response", "kinds"):
        table.add_column(col)
    for entry in api_table():
        req = ", ".join(entry.request.model_fields) if entry.request else "(sensor_msgs)"
        res = ", ".join(entry.response.model_fields) if entry.response else ""
        table.add_row(entry.suffix, entry.direction, entry.ros_type, f"{req} -> {res}" if res else req,
                      ",".join(sorted(entry.kinds)))
    out.print(table)
    total = 0
    for agent in world.agents:
        n = len(entries_for(agent.kind))
        total += n
        out.print(f"  {agent.name} ({agent.kind}): {n} endpoints, e.g. {agent.name}{entries_for(agent.kind)[0].suffix}")
    out.print(f"{len(world.agents)} agents, {total} endpoints")


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
    for info in infos:
        status = ", ".join(info.provided()) or "-" if info.loaded else f"FAILED: {info.error}"
        table.add_row(info.name, info.distribution, info.version, status)
    out.print(table)
    if not infos:
        out.print("no plugins installed (pip install sigcore-backend-mujoco)")


def main() -> None:
    """Console-script entry point."""
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    plugins.load_plugins()
    plugins.add_commands(app)
    app()
