"""The commands that look at a world or at the installation without running anything: ``check`` (a world file
validated and built), ``api`` (every endpoint a run will have), ``interfaces`` (the ROS 2 interface files),
``plugins``, ``spawnables`` and ``worlds`` (what is installed or found)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table
from rich.text import Text

from .. import plugins
from ..world import WorldError, parse_world
from .common import Seed, WorldPath, build_sim, check_backend, draw_world, err, fail, out, parse_seed, read_world
from .transport import DEFAULT_TRANSPORT, check_endpoints, pick_transport


def check(
    world_file: WorldPath,
    backend: Annotated[str, typer.Option(help="backend to build it with", callback=check_backend)] = "mujoco",
    transport: Annotated[str | None, typer.Option(
        help=f"transport whose endpoints to check; default '{DEFAULT_TRANSPORT}' when it can start; 'none'")] = None,
    seed: Seed = None,
) -> None:
    """Validate a world file: syntax, references, controllers, plugins, that the backend builds it, and that the
    transport can create every endpoint (valid ROS names, none used twice). --seed N checks the world its
    <randomize> draws with N and prints what was drawn: each entity's x y z [m] and yaw [rad], each option picked."""
    seed_value = parse_seed(seed)
    transport_obj = pick_transport(transport)
    world = read_world(world_file)
    layout = draw_world(world, seed_value, "checked with the poses as written")
    if layout is not None and world.randomize is not None:
        out.print(f"{world_file}: seed {layout.seed} draws")
        for pick in layout.picks:
            choice = next(c for c in world.randomize.choices if c.entity == pick.entity)
            out.print(f"  {pick.entity:<16} option {pick.option + 1} of {len(choice.options)} (line {pick.line})")
        for p in layout.placements:
            x, y, z = (v + 0.0 for v in p.xyz)
            on = f"  on {p.surface}" if p.surface is not None else ""
            out.print(f"  {p.entity:<16} x {x:10.6f}  y {y:10.6f}  z {z:9.6f}  yaw {p.rpy[2] + 0.0:9.6f}{on}")
    sim = build_sim(world_file, backend, world=layout.world if layout is not None else world)
    check_endpoints(transport_obj, sim)
    with_transport = f", endpoints of '{transport_obj.name}' checked" if transport_obj is not None else ""
    out.print(f"{world_file}: ok ({len(sim.entities)} agents, built with '{backend}'{with_transport})")


def api(
    world_file: Annotated[Path | None, typer.Argument(exists=True, dir_okay=False, help="world XML file")] = None,
    markdown: Annotated[bool, typer.Option("--markdown", help="print the reference as Markdown")] = False,
    backend: Annotated[str, typer.Option(help="physics backend", callback=check_backend)] = "mujoco",
    transport: Annotated[str, typer.Option(help="the transport whose endpoints to list, or 'none'")] = "ros2",
    every: Annotated[bool, typer.Option("--all", help="also print each agent's endpoints one per line")] = False,
) -> None:
    """Print every endpoint a run of a world will have: the agents' API (with the features'), the publications
    of the core and the features, and the transport's own topics and services."""
    from ..api.docs import api_markdown

    if markdown:
        print(api_markdown())
        return
    if world_file is None:
        raise fail(["give a world file (or --markdown for the reference)"])
    sim = build_sim(world_file, backend)
    entries = sim.api_entries()
    agent_topics = {p.topic for p in sim.publications.declared if p.agent}
    described: dict[str, str] = {}
    if transport != "none":
        try:
            described = plugins.get_transport(transport)().describe(sim)
        except plugins.PluginError as e:
            raise fail([str(e)]) from None
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


def interfaces(
    out_dir: Annotated[Path, typer.Option("--out", help="interface package directory")] = Path(
        "interfaces/sigcore_msgs"),
) -> None:
    """Write the sigcore_msgs ROS 2 interface files (msg/, srv/) generated from the API table."""
    from ..api.interfaces import write_interfaces

    files = write_interfaces(out_dir)
    out.print(f"{len(files)} interface files in {out_dir}")


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


def spawnables_cmd(
    world_file: Annotated[Path | None, typer.Argument(exists=True, dir_okay=False, help="world XML file (its "
                                                       "models/ folder counts too)")] = None,
) -> None:
    """List the models a spawn request may name as model://NAME: name, origin, description."""
    from ..world.models import World
    from ..world.spawnables import find_spawnables

    try:
        world = parse_world(world_file) if world_file is not None else World()
    except WorldError as e:
        raise fail([str(i) for i in e.issues]) from None
    found = find_spawnables(world, plugins.spawnables().values())
    table = Table(title="spawnables (model://NAME)")
    for col in ("name", "origin", "description"):
        table.add_column(col)
    for s in found:  # cells as Text: names and descriptions are never read as markup
        table.add_row(Text(s.name), Text(s.origin), Text(s.description))
    out.print(table)
    if not found:
        out.print("no spawnables (folders of worlds/models with a spawnable.xml, or a plugin's)")


def worlds_cmd(
    paths: Annotated[list[Path] | None, typer.Argument(help="world files or folders to list besides worlds/ and the "
                                                      "plugins' (as sigcore run --worlds adds them)")] = None,
) -> None:
    """List the worlds a running simulation may load (load_world): name, file, where found, tags, description."""
    from ..world.catalogue import default_sources, find_worlds

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
