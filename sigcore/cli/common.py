"""What every ``sigcore`` command shares: its two consoles and how it fails, the options several commands take
(world file, controllers, viewer, ``--seed``, ``--backend``), and how a command reads, draws and builds a world,
each failure printed as what it is."""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.console import Console

from .. import plugins
from ..errors import SigcoreError
from ..world import WorldError, parse_world

if TYPE_CHECKING:
    from ..sim import Simulation
    from ..world import World
    from ..world.randomize import Layout

out = Console(highlight=False, soft_wrap=True, markup=False)
"""Standard output: results, tables, reports."""
err = Console(stderr=True, highlight=False, markup=False, soft_wrap=True)
"""Standard error: progress and problems, one line per message, never wrapped."""


def fail(lines: list[str], code: int = 2) -> typer.Exit:
    """Print ``lines`` on standard error and return the exit to raise (``raise fail([...])``): 2 for bad input (the
    default), 1 for what happened, 3 for a run that stopped early."""
    for line in lines:
        err.print(line, markup=False, soft_wrap=True)
    return typer.Exit(code)


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


def backend_names() -> list[str]:
    return sorted(plugins.backends())


def check_backend(value: str) -> str:
    names = backend_names()
    if value not in names:
        raise typer.BadParameter(f"'{value}' is not installed; available: {', '.join(names) or 'none'}")
    return value


def parse_seed(text: str | None) -> int | None:
    """The value of ``--seed`` (exit 2 unless an integer 0 <= N <= :data:`MAX_SEED`)."""
    if text is None:
        return None
    digits = text.strip()
    if not re.fullmatch(r"[0-9]{1,20}", digits) or int(digits) > MAX_SEED:
        raise fail([f"--seed {text!r}: not a seed; valid: an integer 0 <= N <= {MAX_SEED} (the same N gives the same "
                    "world)"])
    return int(digits)


def read_world(world_file: Path) -> World:
    """The world file, parsed (exit 2 with its issues)."""
    try:
        return parse_world(world_file)
    except WorldError as e:
        raise fail([str(i) for i in e.issues]) from None


def draw_world(world: World, seed: int | None, unseeded: str) -> Layout | None:
    """``world`` drawn with ``--seed`` (its ``<randomize>``, and the seed of its sensor noise), or None without it;
    says on stderr what the seed does (or, without one, that the poses are the file's: ``unseeded``)."""
    from ..world.randomize import draw

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
        raise fail([str(i) for i in e.issues]) from None


def build_sim(world_file: Path, backend: str, controllers: list[str] | None = None, world: World | None = None) \
        -> Simulation:
    """Build the simulation of ``world`` (else of the file as written); every failure is printed as what it is
    (world file, controller, feature, backend)."""
    from ..agent.exceptions import ApiError
    from ..errors import BackendError
    from ..sim import FeatureError, Simulation

    overrides: dict[str, str] = {}
    for item in controllers or []:
        agent, sep, spec = item.partition("=")
        if not sep or not agent or not spec:
            raise fail([f"--controller wants AGENT=CONTROLLER (e.g. robot_000=cleanup.robot), got {item!r}"])
        overrides[agent] = spec
    if world is None:
        world = read_world(world_file)
    try:
        return Simulation(world, backend, overrides)  # fires sigcore_world_loaded
    except BackendError as e:  # first (a BackendRefusal is an ApiError too); located at the entity it names
        raise fail([f"{entity_location(world, str(e))}: cannot build the world with backend '{backend}': {e}"]) \
            from None
    except ApiError as e:
        raise fail([f"{world_file}: --controller: {e}"]) from None
    except WorldError as e:  # the world file, a controller that cannot be created, a feature's attributes
        raise fail([str(i) for i in e.issues]) from None
    except FeatureError as e:  # names the feature and its <plugin> line
        raise fail([str(e)]) from None
    except plugins.PluginError as e:
        raise fail([f"{world_file}: {e}"]) from None
    except SigcoreError as e:
        raise fail([f"{world_file}: {e}"]) from None
    except KeyboardInterrupt:
        raise fail(["interrupted while building the world"], 130) from None
    except (Exception, SystemExit) as e:  # not one of ours: the backend's engine (or a bug) failed
        raise fail([f"{entity_location(world, str(e))}: cannot build the world with backend '{backend}': "
                    f"{type(e).__name__}: {e}"]) from None


def entity_location(world: World, text: str) -> str:
    """``file:line:column`` of the first agent that ``text`` names as ``kind 'name'`` (else of ``<world>``)."""
    for match in re.finditer(r"\b(?:robot|object|human|agent|entity) '([A-Za-z][A-Za-z0-9_]*)'", text):
        line, column = world.location(match.group(1))
        if line:
            return f"{world.source}:{line}:{column}"
    line, column = world.location("")
    return f"{world.source}:{line or 1}:{column or 1}"
