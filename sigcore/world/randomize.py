"""Seeded worlds: a world's ``<randomize>`` drawn with a seed (``sigcore run --seed N``; ``docs/world-format.md``,
"<randomize>").

:func:`check` finds, when the file is read and before any seed, what in a ``<randomize>`` does not fit its world.
:func:`sample` draws a new world: first every ``<choose>`` (an option, by weight), then every ``<pose>`` (a yaw, a
surface, a position), each in the file's order. A drawn footprint (the entity's box turned by its orientation, seen
from above, grown by its clearance) that overlaps one drawn before, or an entity left in place whose height range
meets its own, is drawn again, up to ``attempts`` times; then :class:`RandomizeError` says where and what to change.

The same seed gives the same world on any machine: one ``random.Random(seed)`` (Python keeps its ``random()``
sequence the same on every platform and version), only ``random()`` drawn, trigonometry from :mod:`math` (not numpy's
CPU-dependent loops), every drawn value rounded to 1e-6 before it is tested, so the footprint tested is the one
written and printed values are stable.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

from .exceptions import RandomizeError, SeedError, WorldIssue
from .footprints import (
    LEVEL,
    Bounds,
    Box,
    Rect,
    Surface,
    bounds_of,
    grown,
    overlap_xy,
    overlap_z,
    placed_box,
    surface_of,
)
from .models import AgentModel, BareAgent, Entity, Object, Pose, World
from .randomization import Choice, Option, RandomPose, with_option

REST_GAP = 0.001
"""Height of an entity put on a surface above its top [m], so that it settles without starting in contact."""

_ROUND = 6
"""Drawn values are rounded to this many decimals (1e-6 m, 1e-6 rad)."""


@dataclass(frozen=True)
class Placement:
    """Where :func:`draw` put an entity of a ``<pose>``.

    Attributes:
        entity: Its name.
        xyz: Its position in world [m].
        rpy: Its roll, pitch (the file's) and yaw [rad].
        surface: The entity it was put on (``on``), or None.
        draws: How many draws it took (1 when the first fit).
    """

    entity: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    surface: str | None
    draws: int


@dataclass(frozen=True)
class Pick:
    """The option :func:`draw` picked for the object of a ``<choose>``.

    Attributes:
        entity: The object.
        option: Index of the option among the ``<choose>``'s, from 0.
        line: The option's line in the world file.
    """

    entity: str
    option: int
    line: int


@dataclass(frozen=True)
class Layout:
    """A world drawn with a seed and what was drawn for it (:func:`draw`)."""

    seed: int
    world: World
    picks: tuple[Pick, ...]
    placements: tuple[Placement, ...]


# ---------------------------------------------------------------------------------------------------------- checking


def check(world: World) -> list[WorldIssue]:
    """What in ``world``'s ``<randomize>`` does not fit the world, each at its ``file:line:column``; the parser calls
    this once the rest of the file is valid, so every such problem is found before any seed.

    A ``<pose>`` must name a robot, object or human, once, whose bounds (every ``<choose>`` variant's) are known;
    its ``on`` entities must be other entities left in place, level, with known bounds, and their tops must meet its
    ``region``; its ``area`` must be a ``<named_pose>`` with ``bounds``. A ``<choose>`` names its object once.
    """
    spec = world.randomize
    if spec is None:
        return []
    issues: list[WorldIssue] = []
    bodies = {e.name: e for e in world.entities}
    changed = [c.entity for c in spec.choices] + [p.entity for p in spec.poses]
    firsts: dict[tuple[str, str], RandomPose | Choice] = {}
    items: list[tuple[RandomPose | Choice, str]] = [*((c, "choose") for c in spec.choices),
                                                    *((p, "pose") for p in spec.poses)]
    for item, tag in items:
        first = firsts.setdefault((tag, item.entity), item)
        if first is not item:
            issues.append(_issue(world, item, "entity", f"'{item.entity}' is in a <{tag}> already (first on line "
                                                        f"{first.line}); valid: one <{tag}> per entity", tag))
    for pose in spec.poses:
        if firsts[("pose", pose.entity)] is not pose:
            continue
        entity = bodies.get(pose.entity)
        if entity is None:
            bodiless = any(a.name == pose.entity for a in world.agents)
            what = f"'{pose.entity}' is an <agent>, which has no body" if bodiless else f"no entity '{pose.entity}'"
            issues.append(_issue(world, pose, "entity", f"{what}; valid: a robot, object or human: "
                                                        f"{', '.join(bodies) or 'none'}"))
            continue
        for model, its_world, which in _variants(world, entity, spec.choices):
            if bounds_of(model, its_world) is None:
                issues.append(_issue(world, pose, "entity", f"'{entity.name}'{which} has no bounds (no visual "
                                                            "that sigcore reads), so no footprint; valid: an entity "
                                                            "with visuals: primitives, URDF visuals, .obj and .stl "
                                                            "meshes"))
        if pose.area is not None:
            issues.extend(_area_issues(world, pose))
        for name in pose.on or ():
            problem = _surface_problem(world, pose, name, bodies, changed)
            if problem is not None:
                issues.append(_issue(world, pose, *problem))
    return issues


def _variants(world: World, entity: Entity, choices: tuple[Choice, ...]) -> list[tuple[Entity, World, str]]:
    """``entity`` as each option of its ``<choose>`` makes it (with the world that holds it), or as it is."""
    choice = next((c for c in choices if c.entity == entity.name), None)
    if choice is None:
        return [(entity, world, "")]
    out: list[tuple[Entity, World, str]] = []
    for option in choice.options:
        model = variant(entity, option)
        agents = tuple(model if a.name == entity.name else a for a in world.agents)
        out.append((model, world.with_agents(agents), f" with the <option> of line {option.line}"))
    return out


def _area_issues(world: World, pose: RandomPose) -> list[WorldIssue]:
    bounded = [p.name for p in world.named_poses if p.bounds is not None]
    named = next((p for p in world.named_poses if p.name == pose.area), None)
    if named is not None and named.bounds is not None:
        return []
    what = f"no <named_pose> '{pose.area}'" if named is None else f"<named_pose> '{pose.area}' has no 'bounds'"
    return [_issue(world, pose, "area", f"{what}; valid: a named pose with bounds: {', '.join(bounded) or 'none'}")]


def _surface_problem(world: World, pose: RandomPose, name: str, bodies: dict[str, Entity],
                     changed: list[str]) -> tuple[str, str] | None:
    """``(attribute, message)`` when entity ``name`` cannot be a surface of ``pose``, else None."""
    valid = ", ".join(n for n in bodies if n not in changed) or "none"
    if name == pose.entity:
        return "on", f"'{name}' cannot be put on itself; valid: other entities, left in place: {valid}"
    if name not in bodies:
        return "on", f"no entity '{name}'; valid: robots, objects or humans left in place: {valid}"
    if name in changed:
        return "on", f"'{name}' is itself changed by <randomize>; valid: entities left in place: {valid}"
    entity = bodies[name]
    roll, pitch, _ = entity.pose.rpy
    if abs(roll) > LEVEL or abs(pitch) > LEVEL:
        return "on", (f"'{name}' is tilted (roll {roll:g}, pitch {pitch:g} rad), so its top is not level; valid: a "
                      "surface entity whose pose has roll = pitch = 0")
    surface = surface_of(entity, world)
    if surface is None:
        return "on", (f"'{name}' has no bounds (no visual that sigcore reads), so no top; valid: an entity with "
                      "visuals: primitives, URDF visuals, .obj and .stl meshes")
    if pose.region is not None:
        x0, y0, x1, y1 = surface.world_box(surface.rect)
        r = pose.region
        if max(x0, r[0]) > min(x1, r[2]) or max(y0, r[1]) > min(y1, r[3]):
            return "region", (f"{' '.join(f'{v:g}' for v in r)} does not meet the top of '{name}' (x {x0:g} to "
                              f"{x1:g}, y {y0:g} to {y1:g}); valid: a region over part of every surface in 'on'")
    return None


# ---------------------------------------------------------------------------------------------------------- drawing


def sample(world: World, seed: int) -> World:
    """``world`` with its ``<randomize>`` drawn with ``seed``: a new world, the given one untouched.

    Args:
        world: A parsed world; without ``<randomize>`` it is returned as it is (a copy), marked as drawn.
        seed: An integer >= 0; the same seed gives the same world.

    Returns:
        The new world; :attr:`World.sample_seed` is ``seed``; its sensor-noise seed (``World.seed``) is the file's.

    Raises:
        SeedError: ``seed`` is not an integer >= 0.
        RandomizeError: an entity found no free place in ``attempts`` draws.
    """
    return draw(world, seed).world


def apply_seed(world: World, seed: int) -> World:
    """``world`` as ``sigcore run --seed`` runs it: drawn with ``seed`` (:func:`sample`), and ``seed`` as the seed of
    its sensor noise (``World.seed``).

    Raises:
        SeedError: ``seed`` is not an integer >= 0.
        RandomizeError: an entity found no free place in ``attempts`` draws.
    """
    return draw(world, seed, noise=True).world


def draw(world: World, seed: int, noise: bool = False) -> Layout:
    """Draw ``world``'s ``<randomize>`` with ``seed``: the new world and what was drawn (see :func:`sample`).

    Args:
        world: A parsed world.
        seed: An integer >= 0.
        noise: Also make ``seed`` the new world's sensor-noise seed (``World.seed``), as :func:`apply_seed`.
    """
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise SeedError(f"seed {seed!r}: valid: an integer >= 0 (the same seed gives the same world)")
    spec = world.randomize
    agents: list[AgentModel] = list(world.agents)
    picks: list[Pick] = []
    placements: list[Placement] = []
    if spec is not None:
        rng = random.Random(seed)
        index = {agent.name: i for i, agent in enumerate(agents)}
        for choice in spec.choices:
            k = _weighted(rng, [o.weight for o in choice.options])
            agents[index[choice.entity]] = variant(agents[index[choice.entity]], choice.options[k])
            picks.append(Pick(choice.entity, k, choice.options[k].line))
        chosen = world.with_agents(tuple(agents))
        moving = [p.entity for p in spec.poses]
        fixed = []
        for entity in chosen.entities:
            bounds = bounds_of(entity, chosen) if entity.name not in moving else None
            if bounds is not None:
                fixed.append((entity.name, placed_box(bounds, entity.pose.xyz, entity.pose.rpy)))
        placed: list[tuple[str, Box]] = []
        for pose in spec.poses:
            agent = agents[index[pose.entity]]
            assert not isinstance(agent, BareAgent), "check() refused a <pose> of a bodiless agent"
            placement, box = _place(rng, chosen, agent, pose, spec.attempts, fixed, placed)
            placed.append((pose.entity, box))
            agents[index[pose.entity]] = rebuilt(agent, pose=Pose(xyz=placement.xyz, rpy=placement.rpy))
            placements.append(placement)
    drawn = world.drawn(tuple(agents), seed)
    if noise:
        drawn = drawn.model_copy(update={"seed": seed})
    return Layout(seed, drawn, tuple(picks), tuple(placements))


def variant(agent: AgentModel, option: Option) -> Object:
    """The object ``agent`` as ``option`` changes it (validated; the parser checked that it validates)."""
    assert isinstance(agent, Object), "the parser refused a <choose> of anything but an <object>"
    data = {k: getattr(agent, k) for k in Object.model_fields if k in agent.model_fields_set}
    return Object.model_validate(with_option(data, option.attributes))


def rebuilt(agent: Entity, pose: Pose) -> Entity:
    """``agent`` with ``pose``, validated again; the attributes it was given stay the ones given."""
    data = {k: getattr(agent, k) for k in type(agent).model_fields if k in agent.model_fields_set}
    return type(agent).model_validate({**data, "pose": pose})


def _place(rng: random.Random, world: World, entity: Entity, pose: RandomPose, attempts: int,
           fixed: list[tuple[str, Box]], placed: list[tuple[str, Box]]) -> tuple[Placement, Box]:
    """Draw ``entity``'s pose until its footprint is free (at most ``attempts`` times)."""
    bounds = bounds_of(entity, world)
    if bounds is None:
        raise RandomizeError([_issue(world, pose, None, f"'{entity.name}' (as its <choose> picked it) has no bounds "
                                                        "(no visual that sigcore reads), so no footprint; valid: an "
                                                        "entity with visuals: primitives, URDF visuals, .obj and "
                                                        ".stl meshes")])
    roll, pitch, yaw = entity.pose.rpy
    surfaces = [surface for surface in (_surface(world, name) for name in pose.on or ()) if surface is not None]
    region = pose.region if pose.area is None else area_rect(world, pose.area)
    misses: dict[str, int] = {}
    blockers: list[str] = []
    for attempt in range(1, attempts + 1):
        if pose.yaw is not None:
            yaw = _round(_uniform(rng, *pose.yaw))
        rpy = (roll, pitch, yaw)
        surface: Surface | None = None
        if surfaces:
            surface = surfaces[min(int(rng.random() * len(surfaces)), len(surfaces) - 1)]
            spot, why = _spot(rng, surface, bounds, rpy, pose.clearance, region)
            if spot is None:
                misses[why] = misses.get(why, 0) + 1
                continue
            xyz = spot
        else:
            assert region is not None, "check() made sure a <pose> has a region, a surface or an area"
            z = pose.z if pose.z is not None else entity.pose.xyz[2]
            xyz = (_round(_uniform(rng, region[0], region[2])), _round(_uniform(rng, region[1], region[3])), z)
        box = placed_box(bounds, xyz, rpy)
        blocker = _blocker(grown(box, pose.clearance), fixed, placed)
        if blocker is not None:
            misses["overlap"] = misses.get("overlap", 0) + 1
            if blocker not in blockers:
                blockers.append(blocker)
            continue
        return Placement(entity.name, xyz, rpy, surface.name if surface else None, attempt), box
    raise RandomizeError([_issue(world, pose, None, _no_place(pose, attempts, misses, blockers))])


def _spot(rng: random.Random, surface: Surface, bounds: Bounds, rpy: tuple[float, float, float], clearance: float,
          region: Rect | None) -> tuple[tuple[float, float, float] | None, str]:
    """A position drawn uniformly where an entity of ``bounds`` turned by ``rpy`` rests on ``surface`` with its
    footprint ``clearance`` inside the edges (and its position in ``region``); None and why when there is none, or
    when the draw fell off a turned top."""
    room = surface.room(bounds, rpy, clearance)
    if room is None:
        return None, f"were too large for the top of {surface.name} at their yaw"
    rect, height = room
    x0, y0, x1, y1 = surface.world_box(rect)
    if region is not None:
        x0, y0, x1, y1 = max(x0, region[0]), max(y0, region[1]), min(x1, region[2]), min(y1, region[3])
        if x0 > x1 or y0 > y1:
            return None, f"left no room on the top of {surface.name} inside the region"
    x, y = _round(_uniform(rng, x0, x1)), _round(_uniform(rng, y0, y1))
    if not surface.axis_aligned:
        u, v = surface.local(x, y)
        slack = 10.0 ** -_ROUND
        if not (rect[0] - slack <= u <= rect[2] + slack and rect[1] - slack <= v <= rect[3] + slack):
            return None, f"fell off the (turned) top of {surface.name}"
    return (x, y, _round(height + REST_GAP)), ""


def _surface(world: World, name: str) -> Surface | None:
    entity = world.agent(name)
    return surface_of(entity, world) if not isinstance(entity, BareAgent) else None


def area_rect(world: World, name: str) -> Rect:
    """The rectangle in world of the named pose ``name``'s bounds (check() made sure it has some)."""
    pose = next(p for p in world.named_poses if p.name == name)
    assert pose.bounds is not None, "check() refused an area without bounds"
    x, y, _ = pose.pose.xyz
    b = pose.bounds
    return x + b[0], y + b[1], x + b[3], y + b[4]


def _no_place(pose: RandomPose, attempts: int, misses: dict[str, int], blockers: list[str]) -> str:
    where = []
    if pose.on is not None:
        where.append(f"on {' or '.join(pose.on)}")
    if pose.region is not None:
        where.append(f"{'within' if pose.on else 'in'} region {' '.join(f'{v:g}' for v in pose.region)}")
    if pose.area is not None:
        where.append(f"in area '{pose.area}'")
    why = []
    for reason, count in misses.items():
        if reason == "overlap":
            names = ", ".join(blockers[:5]) + (f" and {len(blockers) - 5} more" if len(blockers) > 5 else "")
            why.append(f"{count} overlapped {names} (with a clearance of {pose.clearance:g} m)")
        else:
            why.append(f"{count} {reason}")
    return (f"no free place for '{pose.entity}' {' '.join(where)} in {attempts} draws: {'; '.join(why)}; valid: a "
            "larger region or surface, fewer entities drawn there, a smaller 'clearance', or more draws "
            "(<randomize attempts>)")


def _blocker(box: Box, fixed: list[tuple[str, Box]], placed: list[tuple[str, Box]]) -> str | None:
    """The first entity ``box`` overlaps: one drawn before (seen from above), or one left in place whose height
    range meets ``box``'s (so a thing resting on a surface does not collide with it)."""
    for name, other in placed:
        if overlap_xy(box, other):
            return name
    for name, other in fixed:
        if overlap_xy(box, other) and overlap_z(box, other):
            return name
    return None


# ---------------------------------------------------------------------------------------------------------- numbers


def _uniform(rng: random.Random, lo: float, hi: float) -> float:
    return lo + (hi - lo) * rng.random()


def _weighted(rng: random.Random, weights: list[float]) -> int:
    """An index drawn with chances proportional to ``weights``."""
    r = rng.random() * sum(weights)
    total = 0.0
    for i, w in enumerate(weights):
        total += w
        if r < total:
            return i
    return len(weights) - 1


def _round(value: float) -> float:
    return round(value, _ROUND) + 0.0  # + 0.0: no -0.0


def _issue(world: World, item: RandomPose | Choice, attribute: str | None, text: str,
           element: str = "pose") -> WorldIssue:
    """An issue at ``item``'s ``attribute`` (at its element when the attribute is not written)."""
    line, column = item.location(attribute)
    return WorldIssue(world.source, line, column, element, attribute if attribute in item.positions else None, text)

