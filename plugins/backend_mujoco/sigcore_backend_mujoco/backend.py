"""The MuJoCo implementation of :class:`sigcore.backend.Backend`.

Runtime techniques (each verified against MuJoCo 4.0 in ``tests/backends/test_mujoco_runtime_entities.py``):

* **Step cost.** :meth:`MujocoBackend.step` is ``mj_step`` plus a counter increment; only when an entity is
  held or a wrench/torque was applied does it run a vectorised post-step (restore held ``qpos``, zero their
  ``qvel``, clear ``xfrc_applied``/``qfrc_applied``). :meth:`MujocoBackend.step_batch` takes many such steps in
  one call to a compiled loop (:mod:`.steps`), the same bit for bit.
* **Fresh kinematics on read.** After ``mj_step``, ``xpos`` & co. describe the state *before* the integration.
  The first read after a step or a state write runs ``mj_kinematics``, ``mj_comPos`` and ``mj_comVel`` once,
  so poses, velocities and rays match ``qpos``/``qvel`` exactly. The next ``mj_step`` recomputes all of it, so
  this does not change the trajectory.
* **Dynamics off** (held entities): after every step their ``qpos`` slice is restored and their ``qvel`` slice
  zeroed; ``set_pose``/``set_joint_angle`` update the held values. Static objects have no joints at all.
* **Gravity off:** ``body_gravcomp = 1`` on the entity's bodies (a force of ``-m g`` at each body's centre of
  mass), with ``mjModel.flg_gravcomp`` set, which MuJoCo needs to apply gravity compensation at all.
* **Wrenches** go to ``xfrc_applied`` (force then torque, world frame, applied at the body's centre of mass);
  joint torques to ``qfrc_applied``.
* **Mass:** ``body_mass`` and ``body_inertia`` of the entity's bodies scaled, then ``mj_setConst`` (on a
  scratch ``MjData``) recomputes the derived constants.
* **Reset** restores a copy of the model taken after build (gains, masses, gravity compensation, collision
  bits, moved static bodies, weld poses) and the initial ``qpos``/``qvel``/``ctrl``; entities added while running
  come back as added, those removed stay removed.
* **Adding and removing entities** recompiles the world's spec once per call and carries every surviving
  element's state and run-time model values over by name, bit for bit (:mod:`.carry`, :mod:`.recompile`).
"""

from __future__ import annotations

import copy
import logging
from collections.abc import Collection, Sequence
from typing import ClassVar

import mujoco
import numpy as np
import numpy.typing as npt

from sigcore.backend import Array, Renderer
from sigcore.errors import BackendError, BackendRefusal
from sigcore.world.models import World

from . import grasp
from .builder import add_to_spec, build_spec, rebuild_spec
from .carry import carry_data, carry_model, element_map, warm_start
from .collision import CollisionBits
from .contacts import ContactMap
from .joints import MujocoJoints
from .layout import Layout
from .modes import MujocoModes
from .plan import EntityPlan, WeldPlan
from .rays import RayCaster
from .recompile import compile_world
from .state import MujocoState
from .steps import HeldArrays, compiled

log = logging.getLogger("sigcore.backend.mujoco")

STABILITY_CHECK_MASK = 255
"""MuJoCo's bad-acceleration warning counter is read when ``step & STABILITY_CHECK_MASK == 0`` (every 256 steps,
0.5 s at the default timestep: reading it every step would cost 1 % of the step)."""
STABILITY_SHIFT = (STABILITY_CHECK_MASK + 1).bit_length() - 1


class MujocoBackend(MujocoState, MujocoModes, MujocoJoints):
    """MuJoCo physics (the default backend). See the module docstring for how each feature is done; the parts are
    mixins (:mod:`.base`).

    Attributes:
        model: The compiled ``mujoco.MjModel`` (after :meth:`build`; a fresh copy after :meth:`reset`).
        data: Its ``mujoco.MjData``. Both are for reading (e.g. rendering); writing to them bypasses the
            backend's bookkeeping.
    """

    name: ClassVar[str] = "mujoco"
    title: ClassVar[str] = "MuJoCo"
    replay_tolerance: ClassVar[float] = 0.0
    """MuJoCo is deterministic to the bit: a replay reproduces every recorded pose exactly."""

    def __init__(self) -> None:
        self._built = False

    # ------------------------------------------------------------------ life cycle
    def build(self, world: World) -> None:
        """Compile ``world`` into a MuJoCo model (see :mod:`.builder` for the layout).

        Raises:
            BackendError: a model file is missing or MuJoCo rejects the model; the message names the entity.
        """
        spec, plans, welds = build_spec(world)
        model, layout = compile_world(spec, plans, welds, ())
        self._install(spec, plans, welds, model, copy.copy(model), mujoco.MjData(model), layout)
        self._rays = RayCaster()
        self._bits = CollisionBits()
        self._grasps: set[tuple[str, str, str]] = set()
        self._built = True
        self._restart()

    def _install(self, spec: mujoco.MjSpec, plans: list[EntityPlan], welds: list[WeldPlan], model: mujoco.MjModel,
                 model0: mujoco.MjModel, data: mujoco.MjData, layout: Layout) -> None:
        """Make ``model`` the running model (``model0``: its state for :meth:`reset`)."""
        self._spec, self._plans, self._welds = spec, plans, welds
        self.model, self._model0, self.data = model, model0, data
        self._layout: Layout = layout
        self._entities = layout.entities
        self._pose_rows = {}
        self._contact_map = ContactMap(layout.geom_part, layout.part_entity)
        self._scratch = None
        self._servos = [j.servo for e in self._entities.values() for j in e.joints.values() if j.servo is not None]

    def _restart(self) -> None:
        """Initial state on the current model (after build or reset)."""
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        for servo in self._servos:
            servo.restart(m, d)
        self._tick = 0
        self._unstable = 0
        self._synced = -1
        self._contacts_tick = -1
        self._read_tick = -1
        self._loop = compiled()
        self.batches = self._loop is not None
        self._held_c: HeldArrays | None = None
        self._contacts: frozenset[tuple[int, int]] = frozenset()
        self._applied = False
        self._held = {e.name for e in self._entities.values() if e.held0}
        for e in self._entities.values():
            self._bits.hold_person(m, e, e.held0)
        self._hold = d.qpos.copy()
        self._rebuild_held()
        mujoco.mj_forward(m, d)

    def step(self) -> None:
        """Advance by one timestep (``mj_step``); then restore held entities and clear applied forces."""
        mujoco.mj_step(self.model, self.data)
        self._tick += 1
        if not self._tick & STABILITY_CHECK_MASK:
            self._check_stability()
        if self._post:
            self._after_step()

    def step_batch(self, n: int, contacts: bool) -> int:
        """Take up to ``n`` steps in one call to the compiled loop (:mod:`.steps`), each one what :meth:`step` does;
        with ``contacts``, stop after the first step whose contacts differ from those before. One :meth:`step`
        instead when there is no compiled loop, a force or torque was applied for the next step, or the current
        contacts were not read (the comparison starts from contacts the core has seen)."""
        loop = self._loop
        if n <= 1 or loop is None or self._applied or (contacts and self._read_tick != self._tick):
            self.step()
            return 1
        held = self._held_c
        if held is None or held.key != (id(self._held_qpos), id(self._held_values), id(self._held_dofs)):
            held = self._held_c = HeldArrays(self._held_qpos, self._held_values, self._held_dofs)
        tick0 = self._tick
        self._tick = tick = tick0 + loop.run(self.model, self.data, n, held, contacts)
        if tick0 >> STABILITY_SHIFT != tick >> STABILITY_SHIFT:  # passed a step where step() checks
            self._check_stability()
        return tick - tick0

    def _check_stability(self) -> None:
        """Report (once per run of the model, then only counted) that MuJoCo found a NaN, infinite or huge
        acceleration, which makes it reset its whole state to the initial one: the entity whose dof it was, and
        what usually causes it."""
        warning = self.data.warning[mujoco.mjtWarning.mjWARN_BADQACC]
        if warning.number <= self._unstable:
            return
        if self._unstable == 0:
            dof = int(warning.lastinfo)
            owner = next((f"{e.kind} '{e.name}'" for e in self._entities.values() if dof in e.dofs), f"dof {dof}")
            log.warning("MuJoCo became unstable within the last %d steps (a NaN, infinite or huge acceleration of "
                        "%s) and reset every body to its initial state; usual causes: huge forces or torques, "
                        "tiny masses, extreme gravity or timestep (logged once; later ones are counted)",
                        STABILITY_CHECK_MASK + 1, owner)
        self._unstable = warning.number

    @property
    def instabilities(self) -> int:
        """How many times MuJoCo reset its state because of a NaN, infinite or huge acceleration since the last
        build or reset (checked every ``STABILITY_CHECK_MASK + 1`` steps)."""
        return int(self._unstable)

    def _after_step(self) -> None:
        d = self.data
        if self._held_qpos.size:
            qpos, qvel = self._hold_views
            if qpos is not None and qvel is not None:
                qpos[:] = self._held_values
                qvel.fill(0.0)
            else:
                d.qpos[self._held_qpos] = self._held_values
                d.qvel[self._held_dofs] = 0.0
        if self._applied:
            d.xfrc_applied[:] = 0.0
            d.qfrc_applied[:] = 0.0
            self._applied = False
        self._post = bool(self._held_qpos.size)

    def reset(self) -> None:
        """Restore the model as built and the initial state; release grasps; restore modes and masses."""
        self.model = copy.copy(self._model0)
        self._bits.clear()
        self._grasps.clear()
        self._restart()

    # ------------------------------------------------------------------ run-time changes
    def add_entities(self, world: World, names: Sequence[str]) -> None:
        """Add the entities ``names`` of ``world``: one recompile of the world's spec, the state carried over
        bit for bit (see :mod:`.carry`); they start at their model pose, at rest, joints held at 0.

        Raises:
            BackendError: an entity cannot be built or MuJoCo rejects it (the message names it); the running
                world is then unchanged.
        """
        self.require_world()
        spec = self._spec.copy()
        plans, welds = add_to_spec(spec, world, names, self._plans)
        self._recompile(spec, [*self._plans, *plans], [*self._welds, *welds], plans)

    def remove_entities(self, world: World, names: Sequence[str]) -> None:
        """Remove the entities ``names``: the world without them laid out anew with the others' elements in the
        same order (:func:`.builder.rebuild_spec`, so nothing of them is left), one compile, the state of the
        others carried over bit for bit (see :mod:`.carry`); what rested on them falls.

        Raises:
            BackendRefusal: a name is not an entity of the running world (nothing is removed).
        """
        gone = set(names)
        for name in names:
            self._entity(name)
        welds = [w for w in self._welds if w.robot not in gone and w.obj not in gone]
        spec, plans = rebuild_spec(world, welds)
        self._recompile(spec, plans, welds, [])

    def _recompile(self, spec: mujoco.MjSpec, plans: list[EntityPlan], welds: list[WeldPlan],
                   added: list[EntityPlan]) -> None:
        """Compile ``spec``, carry the running state over, then switch to it (nothing changes if compiling fails)."""
        model, layout = compile_world(spec, plans, welds, added)
        elements = element_map(self.model, model)
        model0 = copy.copy(model)
        carry_model(self._model0, model0, elements)
        carry_model(self.model, model, elements)
        data = mujoco.MjData(model)
        carry_data(self.data, data, elements)
        warm_start(model, data, elements)
        contacts = self.contacts()
        old_table, old_entities, old_hold = self._layout.part_table, self._entities, self._hold
        self._install(spec, plans, welds, model, model0, data, layout)
        for name, e in self._entities.items():
            before = old_entities.get(name)
            for joint, j in e.joints.items():
                servo = j.servo
                if servo is None:
                    continue
                if before is None:
                    servo.restart(model, data)
                else:
                    old_servo = before.joints[joint].servo
                    assert old_servo is not None
                    servo.mode, servo.torque = old_servo.mode, old_servo.torque
        self._hold = data.qpos.copy()
        for name in self._held & set(self._entities):
            self._hold[self._entities[name].qpos] = old_hold[old_entities[name].qpos]
        self._held = {n for n in self._held if n in self._entities}
        self._held |= {p.name for p in added if self._entities[p.name].held0}
        for p in added:
            self._bits.hold_person(self.model, self._entities[p.name], self._entities[p.name].held0)
        self._rebuild_held()
        self._bits.forget(set(old_entities) - set(self._entities))
        self._grasps = {g for g in self._grasps if g[0] in self._entities and g[2] in self._entities}
        number = {key: i for i, key in enumerate(layout.part_table)}
        pairs = ((number.get(old_table[a]), number.get(old_table[b])) for a, b in contacts)
        self._contacts = frozenset((min(a, b), max(a, b)) for a, b in pairs if a is not None and b is not None)
        self._tick += 1
        self._synced = -1
        self._contacts_tick = self._tick

    # ------------------------------------------------------------------ cameras
    def renderer(self) -> Renderer:
        """A threaded renderer of this world through MuJoCo's OpenGL renderer (:mod:`.render`)."""
        from .render import MujocoRenderer

        self.require_world()
        return MujocoRenderer(self)

    # ------------------------------------------------------------------ introspection
    def parts(self, entity: str) -> list[str]:
        """Part names of ``entity``, main part first (a robot's root link; ``main`` otherwise)."""
        return list(self._entity(entity).parts)

    def joints(self, entity: str) -> list[str]:
        """Movable joints of a robot or a person in URDF order; empty for objects."""
        return list(self._entity(entity).joints)

    # ------------------------------------------------------------------ grasping
    def attach(self, entity: str, part: str, obj: str) -> None:
        """Switch on the weld of ``part`` and ``obj`` at their current relative pose (see :mod:`.grasp`)."""
        robot, target = self._entity(entity), self._entity(obj)
        key = (entity, part, obj)
        if key in self._grasps:
            return
        weld = grasp.weld_id(self._layout, robot, part, target)
        self._sync()
        grasp.activate(self.model, self.data, weld, robot.body(part), target.root)
        self._grasps.add(key)
        self._bits.count(self._bits.grasping, entity, +1)
        self._bits.count(self._bits.grasped, obj, +1)
        self._bits.apply(self.model, robot)
        self._bits.apply(self.model, target)

    def detach(self, entity: str, part: str, obj: str) -> None:
        """Switch the weld off (no effect if not attached)."""
        robot, target = self._entity(entity), self._entity(obj)
        key = (entity, part, obj)
        if key not in self._grasps:
            return
        self.data.eq_active[self._layout.welds[key]] = 0
        self._grasps.discard(key)
        self._bits.count(self._bits.grasping, entity, -1)
        self._bits.count(self._bits.grasped, obj, -1)
        self._bits.apply(self.model, robot)
        self._bits.apply(self.model, target)

    # ------------------------------------------------------------------ contacts and rays
    def contacts(self) -> frozenset[tuple[int, int]]:
        """Part-id pairs in contact in the last step (computed once per step, from ``data.contact``)."""
        if self._contacts_tick != self._tick:
            self._contacts = self._contact_map.pairs(self.data)
            self._contacts_tick = self._read_tick = self._tick
        return self._contacts

    def part_of(self, part_id: int) -> tuple[str, str]:
        """``(entity, part)`` of a part id; ``("ground", "main")`` for 0."""
        table = self._layout.part_table
        if not 0 <= part_id < len(table):
            raise BackendRefusal(f"no part id {part_id}; valid ids: 0..{len(table) - 1}")
        return table[part_id]

    def ray_cast(self, origin: Array, directions: npt.NDArray[np.float64], max_range: float,
                 exclude: str | None = None) -> Array:
        """``mj_multiRay`` against collision geoms, passing through ``exclude``'s geoms (see :mod:`.rays`)."""
        if not self._built:
            raise BackendError("the MuJoCo backend has no world yet; call build(world) first")
        geoms = self._entity(exclude).geoms if exclude is not None else None
        self._sync()
        return self._rays.cast(self.model, self.data, origin, directions, max_range, geoms)

    def ray_hits(self, origin: Array, directions: npt.NDArray[np.float64], max_range: float,
                 among: Collection[str]) -> tuple[Array, list[str | None]]:
        """``mj_multiRay`` with every geom but those of ``among`` set aside (see :mod:`.rays`), and the entity of
        each geom hit."""
        if not self._built:
            raise BackendError("the MuJoCo backend has no world yet; call build(world) first")
        seen = [self._entity(name).geoms for name in among]
        keep = np.concatenate(seen) if seen else np.zeros(0, dtype=np.int64)
        hidden = np.setdiff1d(np.arange(self.model.ngeom, dtype=np.int64), keep)
        self._sync()
        distances = self._rays.cast(self.model, self.data, origin, directions, max_range, hidden)
        table, parts = self._layout.part_table, self._layout.geom_part
        return distances, [table[parts[g]][0] if g >= 0 else None for g in self._rays.hit_geoms.tolist()]
