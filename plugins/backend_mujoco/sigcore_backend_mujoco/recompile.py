"""Compiling a world spec into a model ready to run, at build and after entities were added or removed.

Adding or removing entities while running (:meth:`MujocoBackend.add_entities`, ``remove_entities``) edits a copy of
the world's spec (:func:`.builder.add_to_spec`, :func:`.edit.remove_from_spec`), compiles it with
:func:`compile_world`, and carries the running state over (:mod:`.carry`). Only when all of that succeeded does the
backend switch to the new model: an entity MuJoCo rejects leaves the running world untouched.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco

from sigcore.errors import BackendError

from .layout import EntityIndex, Layout, index_model
from .plan import EntityPlan, WeldPlan


def compile_world(spec: mujoco.MjSpec, plans: Sequence[EntityPlan], welds: Sequence[WeldPlan],
                  new: Sequence[EntityPlan]) -> tuple[mujoco.MjModel, Layout]:
    """Compile ``spec``, index it, and give the entities of ``plans`` that ask for one their total mass.

    Args:
        spec: The world spec (not changed).
        plans: Every entity in it, in world order.
        welds: Every grasp weld in it.
        new: The entities just added (named first when MuJoCo rejects the model).

    Raises:
        BackendError: MuJoCo rejects the model; the message names the entity when MuJoCo's message does, else
            the entities just added.
    """
    _size_arena(spec)
    try:
        model = spec.compile()
    except ValueError as e:
        raise BackendError(compile_error(e, [*new, *plans], new)) from None
    layout = index_model(model, list(plans), list(welds))
    scratch: mujoco.MjData | None = None
    for plan in plans:
        if plan.total_mass is not None:
            scratch = scale_mass(model, layout.entities[plan.name], plan.total_mass, scratch)
    model.eq_data[:, 11] = 0.0  # welds keep the relative pose we give (mj_setConst must not recompute it)
    return model, layout


ARENA_PER_GEOM_PAIR = 4
"""Bytes of MuJoCo's arena per pair of geoms [B]: its collision broadphase takes about 2 x ngeom² bytes at once
(a world of 3,000 static boxes asked for 18 MB of a default 14.7 MB arena and could not step)."""

ARENA_BASE = 1 << 24
"""Arena kept for everything else (contacts, constraints) when the geoms' share is set [B]."""


def _size_arena(spec: mujoco.MjSpec) -> None:
    """Give a spec with many geoms an arena its broadphase fits in: ``ARENA_BASE`` plus ``ARENA_PER_GEOM_PAIR``
    per pair of geoms, when that exceeds MuJoCo's default sizing (about 1,000 geoms and more); smaller worlds keep
    MuJoCo's own size (and their results, bit for bit)."""
    pairs = len(spec.geoms) ** 2
    if ARENA_PER_GEOM_PAIR * pairs > 1 << 22:
        spec.memory = max(spec.memory, ARENA_BASE + ARENA_PER_GEOM_PAIR * pairs)


def scale_mass(model: mujoco.MjModel, e: EntityIndex, mass: float,
               scratch: mujoco.MjData | None) -> mujoco.MjData:
    """Scale the masses and inertias of ``e``'s bodies to total ``mass`` [kg]; then ``mj_setConst``.

    Args:
        model: The model (changed).
        e: The entity.
        mass: Its new total mass [kg], > 0.
        scratch: Data of ``model`` for ``mj_setConst``, or ``None`` to make one.

    Returns:
        The scratch data (for the next call on the same model).

    Raises:
        BackendError: the entity has no mass to scale.
    """
    total = float(model.body_mass[e.bodies].sum())
    if total <= 0.0:
        raise BackendError(f"{e.kind} '{e.name}' has no mass to scale (its URDF has no <inertial>)")
    factor = mass / total
    model.body_mass[e.bodies] *= factor
    model.body_inertia[e.bodies] *= factor
    if scratch is None:
        scratch = mujoco.MjData(model)
    mujoco.mj_setConst(model, scratch)
    return scratch


def compile_error(error: ValueError, plans: Sequence[EntityPlan], new: Sequence[EntityPlan] = ()) -> str:
    """A one-line message for a model MuJoCo cannot compile, naming the entity and hinting at the fix."""
    text = " ".join(str(error).split())
    owner = next((p for p in plans if f"'{p.name}/" in text), None)
    if owner is not None:
        where = f"{owner.kind} '{owner.name}': "
    elif new:
        where = f"adding {', '.join(f'{p.kind} {p.name!r}' for p in new)}: "
    else:
        where = ""
    hint = ""
    if "no decoder found for mesh" in text:
        hint = " (MuJoCo reads .stl, .obj and .msh meshes: convert the collision mesh, e.g. to .stl)"
    if "mass and inertia of moving bodies" in text:
        hint = (" (every link on a movable joint, and the root link of a robot that is not fixed, needs an "
                "<inertial> with positive mass and inertia; MuJoCo takes masses only from <inertial>)")
    return f"{where}MuJoCo cannot compile the world: {text}{hint}"
