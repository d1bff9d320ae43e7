"""The PyBullet implementation of :class:`sigcore.backend.Backend`.

One PyBullet client per backend instance, in ``DIRECT`` mode; every call passes ``physicsClientId``, so any
number of simulations live in one process. Techniques (each checked by ``tests/backends`` and
``tests/backend_bullet``):

* **Stepping.** ``setPhysicsEngineParameter(fixedTimeStep=world.timestep, numSubSteps=0,
  deterministicOverlappingPairs=1)``; :meth:`BulletBackend.step` is ``stepSimulation`` plus, only when needed,
  a pre-step (servo force limits, gravity compensation) and a post-step (held entities).
* **Link frames.** Child links: ``getLinkState`` indices 4/5 (URDF frame). The base: PyBullet keeps it at its
  inertial frame, converted with the URDF ``<inertial><origin>`` (see :mod:`.frames`).
* **Wrenches** go straight to ``applyExternalForce`` (world frame, at the link's centre of mass) and
  ``applyExternalTorque``; PyBullet clears both after every ``stepSimulation``. Joint torques:
  ``TORQUE_CONTROL``, also cleared after a step, added on top of the joint's motor.
* **Gravity off** (PyBullet has only a global gravity): before every step, a force ``-m g`` at the centre of
  mass of each link of the entity.
* **Dynamics off** (held entities): after every step the base pose and joint positions are restored and the
  velocities zeroed (the MuJoCo backend's technique); ``set_pose``/``set_joint_angle`` update the held values.
  Static objects have mass 0 (PyBullet's static bodies) and cannot become dynamic.
* **Persons** (``<human>``): their generated URDF, held with kinematic joints or dynamic as a rigid mannequin
  (see :mod:`.base`); they have no motors: ``set_joint_angle`` poses them.
* **Servos.** Arm joints in position mode: a velocity motor at ``(kp / kv) (target - q)`` whose force limit is
  set before each step to the spring-damper torque ``|kp e - kv qdot|`` (see :mod:`.servo`), at most the gains'
  ``max_torque`` and the URDF ``effort``. Wheels and velocity mode: ``VELOCITY_CONTROL`` with force = the torque
  limit (an exact, torque-limited velocity motor, a brake at 0).
* **Reset:** ``restoreState`` of a state saved after build (poses, velocities, joint states), then grasps
  removed, masses, collision filters, motors and modes restored.
* **Adding and removing while running:** new entities are created in the running client by the builder's code
  (:func:`.builder.build_entity`), removed ones with ``removeBody`` (which also removes their constraints);
  nothing else is touched, so the other bodies move exactly as in a world that never had them, as long as
  nothing touches the new ones (checked by
  ``tests/backends/test_conformance_spawn.py``). PyBullet reuses the ids of removed bodies, and leaves their
  collision-filter pair entries behind: :mod:`.pairs` keeps every entry consistent. Part ids are renumbered in
  world order. The next reset rebuilds the current world (the saved state holds other bodies).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from typing import ClassVar

import numpy as np
import numpy.typing as npt
import pybullet as pb

from sigcore.backend import GROUND, MAIN, Array, Renderer
from sigcore.errors import BackendError, BackendRefusal
from sigcore.world.models import Human, Object, Robot, World

from . import grasp, rays
from .builder import build_entity, build_world
from .contacts import ContactMap
from .joints import BulletJoints
from .layout import BASE, EntityIndex
from .modes import BulletModes
from .pairs import PairFilters
from .servo import ServoBank
from .state import BulletState


class BulletBackend(BulletState, BulletModes, BulletJoints):
    """PyBullet physics. See the module docstring for how each feature is done; the parts are mixins (:mod:`.base`).

    Attributes:
        client: The PyBullet physics client id (after :meth:`build`), for reading (e.g. rendering); writing
            through it bypasses the backend's bookkeeping.
    """

    name: ClassVar[str] = "bullet"
    title: ClassVar[str] = "PyBullet"
    replay_tolerance: ClassVar[float] = 1e-6
    """PyBullet's replays are stated to be within 1e-6 (not assumed bitwise)."""

    def __init__(self) -> None:
        self.client = -1
        self._built = False
        self._builds = 0
        """How many times the world was created in the client (the renderer paints each new body)."""

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # noqa: BLE001 - at interpreter exit pybullet may already be torn down
            pass

    def close(self) -> None:
        """Disconnect the PyBullet client (also done when the backend is garbage-collected)."""
        if self.client >= 0:
            try:
                pb.disconnect(physicsClientId=self.client)
            except pb.error:
                pass
            self.client = -1
            self._built = False

    # ------------------------------------------------------------------ life cycle
    def build(self, world: World) -> None:
        """Create ``world`` in a new ``DIRECT`` client (see :mod:`.builder` for the layout).

        Raises:
            BackendError: a model file is missing or PyBullet rejects a model; the message names the entity.
        """
        self.close()
        self.client = pb.connect(pb.DIRECT)
        self._world = world
        self._populate()

    def _populate(self) -> None:
        """Create the world in the (empty) client and save the initial state."""
        c, world = self.client, self._world
        pb.setPhysicsEngineParameter(fixedTimeStep=world.timestep, numSubSteps=0, deterministicOverlappingPairs=1,
                                     physicsClientId=c)
        pb.setGravity(*world.gravity, physicsClientId=c)
        self._gravity = np.array(world.gravity, dtype=np.float64)
        try:
            self._ground, entities = build_world(c, world)
        except BackendError:
            self.close()
            raise
        self._entities = {e.name: e for e in entities}
        self._builds += 1
        self._pairs = PairFilters()  # the client is new or was reset: it holds no pair entry
        self._collision_off = set()
        self._index()
        self._built = True
        self._restart_motors()
        self._state0 = pb.saveState(physicsClientId=c)
        self._filters_changed = False
        self._entities_changed = False
        self._frozen = set()
        self._restart()

    def _index(self) -> None:
        """Part ids, the contact map and the possible grasps, from ``_entities`` (in world order) and
        ``_world``."""
        world = self._world
        self._part_table: list[tuple[str, str]] = [(GROUND, MAIN)]
        self._part_id: dict[tuple[int, int], int] = {(self._ground, BASE): 0}
        for e in self._entities.values():
            main_id = len(self._part_table)
            for part in e.parts:
                self._part_id[(e.body, e.link(part))] = len(self._part_table)
                self._part_table.append((e.name, part))
            for link in e.links:
                self._part_id.setdefault((e.body, link), main_id)  # a URDF object's links are its main part
        entity_of_body = {e.body: i + 1 for i, e in enumerate(self._entities.values())}
        entity_of_body[self._ground] = 0
        self._contact_map = ContactMap(self._part_id, entity_of_body)
        self._contacts_tick = -1
        self._graspable = {(r.name, g.part, o.name) for r in world.entities if isinstance(r, Robot)
                           for g in r.grippers for o in world.entities
                           if isinstance(o, Object) and o.graspable and not o.static}

    def _restart(self) -> None:
        """Bookkeeping of the initial state (after build or reset)."""
        self._tick = 0
        self._contacts_tick = -1
        self._contacts: frozenset[tuple[int, int]] = frozenset()
        self._grasps: dict[tuple[str, str, str], int] = {}
        self._mass = {n: list(e.masses0) for n, e in self._entities.items()}
        self._nograv = set()
        self._held = {}
        self._posed = set()
        self._posture = {n: [j.initial for j in e.joints.values()] for n, e in self._entities.items()
                         if e.kind == "human"}
        for e in list(self._entities.values()):
            if e.held0:
                self._hold(e, initial=True)

    def _restart_motors(self) -> None:
        self._servos = {}
        for e in self._entities.values():
            self._start_motors(e)

    def _start_motors(self, e: EntityIndex) -> None:
        """Brake ``e``'s wheels and hold its arm joints where they are (a new servo bank); a person has none."""
        c = self.client
        if e.kind == "human":
            return
        bank = ServoBank(e.body)
        for j in e.joints.values():
            if not j.wheel:
                bank.add(j.index, j.kp, j.kv, j.position_gain, j.max_torque)
        if bank.kp:
            self._servos[e.name] = bank
        for j in e.joints.values():
            if j.wheel:
                pb.setJointMotorControl2(e.body, j.index, pb.VELOCITY_CONTROL, targetVelocity=0.0,
                                         force=j.max_torque, physicsClientId=c)
            else:
                j.initial = float(pb.getJointState(e.body, j.index, physicsClientId=c)[0])
                self._position_servo(e, j, j.initial)

    def step(self) -> None:
        """Advance by one timestep (``stepSimulation``), compensating gravity and restoring held entities."""
        if self._nograv:
            self._compensate_gravity()
        for name, bank in self._servos.items():
            if name not in self._held:
                bank.update(self.client)
        pb.stepSimulation(physicsClientId=self.client)
        self._tick += 1
        if self._held:
            self._restore_held()
        if self._posed:
            self._restore_posed()

    def _compensate_gravity(self) -> None:
        c = self.client
        for name in self._nograv:
            if name in self._held or name in self._frozen:
                continue
            e = self._entities[name]
            masses = self._mass[name]
            for link, m in zip(e.links, masses, strict=True):
                if m > 0.0:
                    com = grasp.inertial_pose(c, e.body, link)[0]
                    pb.applyExternalForce(e.body, link, (-m * self._gravity).tolist(), com, pb.WORLD_FRAME,
                                          physicsClientId=c)

    def _restore_held(self) -> None:
        c = self.client
        for name, (pos, orn, angles) in self._held.items():
            e = self._entities[name]
            if not e.welded:
                pb.resetBasePositionAndOrientation(e.body, pos, orn, physicsClientId=c)
                pb.resetBaseVelocity(e.body, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], physicsClientId=c)
            self._reset_joints(e, angles)

    def _restore_posed(self) -> None:
        """Every held person's joints back at its posture, at rest (its base has mass 0: it does not move)."""
        for name in self._posed:
            self._reset_joints(self._entities[name], self._posture[name])

    def reset(self) -> None:
        """Back to the state right after build.

        ``restoreState`` of the state saved after build restores poses, velocities and joint states; grasps are
        removed and masses, motors and modes restored here. If collision filters changed since (a collision
        mode switched, a grasp made), the world is rebuilt in the same client instead: PyBullet re-inserts a
        re-filtered link into the broadphase, which changes the pair order and so, slightly, every later
        contact solution (0.2 mm after 0.5 s for a ball rolling off a hand), and ``restoreState`` does not undo
        that. A rebuild takes about 45 ms for the clean-up world, a restore 0.1 ms. After entities were added or
        removed the world is rebuilt too (``restoreState`` needs the bodies of the saved state): the current
        world from its model, which puts the old entities at their build state and the added ones at their
        as-added state (their model pose, at rest).
        """
        c = self._client()
        if self._filters_changed or self._entities_changed:
            pb.resetSimulation(physicsClientId=c)
            self._populate()
            return
        for e in self._entities.values():
            masses = self._mass[e.name]
            for i, link in enumerate(e.links):
                if masses[i] != e.masses0[i] and not e.static and e.name not in self._frozen:
                    pb.changeDynamics(e.body, link, mass=e.masses0[i], localInertiaDiagonal=list(e.inertia0[i]),
                                      physicsClientId=c)
        pb.restoreState(self._state0, physicsClientId=c)
        self._restart_motors()
        self._restart()

    # ------------------------------------------------------------------ run-time changes
    def add_entities(self, world: World, names: Sequence[str]) -> None:
        """Create the entities ``names`` of ``world`` in the running client (``loadURDF`` / ``createMultiBody``,
        as :meth:`build` does), without touching any existing body.

        Their servos hold their joints at 0 and brake their wheels; static humans are held. Part ids
        are renumbered in world order. :meth:`reset` then rebuilds the world (see there).

        Raises:
            BackendError: an entity cannot be built (naming it); the bodies made by this call are removed again.
        """
        c = self._client()
        missing = [name for name in names if name not in {a.name for a in world.agents}]
        if missing:
            raise BackendRefusal(f"no agent {', '.join(repr(n) for n in missing)} in the world to add; its agents: "
                                 f"{', '.join(a.name for a in world.agents)}")
        made: list[EntityIndex] = []
        try:
            for entity in (world.agent(name) for name in names):
                if entity.name in self._entities or entity.name in (e.name for e in made):
                    raise BackendRefusal(f"entity '{entity.name}' is already in the world; a new entity needs a "
                                         "name not taken")
                if not isinstance(entity, Robot | Object | Human):
                    raise BackendRefusal(f"agent '{entity.name}' has no body (an <agent>): nothing to add")
                made.append(build_entity(c, world, entity))
        except BackendError:
            for e in made:
                pb.removeBody(e.body, physicsClientId=c)
            raise
        self._world = world
        for e in made:
            self._entities[e.name] = e
            self._mass[e.name] = list(e.masses0)
            if e.kind == "human":
                self._posture[e.name] = [j.initial for j in e.joints.values()]
            self._start_motors(e)
            if e.held0:
                self._hold(e, initial=True)
        self._index()
        self._sync_pairs()  # a new body may have the id of a removed one, and its pair entries
        self._entities_changed = True

    def remove_entities(self, world: World, names: Sequence[str]) -> None:
        """Remove the bodies of ``names`` (``removeBody``, which also removes their constraints); every other
        body keeps its state, and one that rested on a removed body falls.

        Grasps that involve them are released first (the core has done so already; this is for safety). Part ids
        are renumbered in world order. :meth:`reset` then rebuilds the world (see there).
        """
        c = self._client()
        gone = [self._entity(name) for name in names]
        for key in [k for k in self._grasps if k[0] in names or k[2] in names]:
            robot, _, obj = key
            self._release(self._grasps.pop(key), self._entities[robot], self._entities[obj])
        for e in gone:
            pb.removeBody(e.body, physicsClientId=c)
            del self._entities[e.name]
            for per_entity in (self._servos, self._mass, self._held, self._posture):
                per_entity.pop(e.name, None)
            for names_set in (self._nograv, self._frozen, self._collision_off, self._posed):
                names_set.discard(e.name)
        self._world = world
        self._index()
        self._entities_changed = True

    # ------------------------------------------------------------------ cameras
    def renderer(self) -> Renderer:
        """A renderer of this world through PyBullet's TinyRenderer, on the simulation's thread (:mod:`.render`)."""
        from .render import BulletRenderer

        self._client()
        return BulletRenderer(self)

    # ------------------------------------------------------------------ introspection
    def parts(self, entity: str) -> list[str]:
        """Part names of ``entity``, main part first: a robot's or a person's URDF links, root first (a person's
        root is ``main``, at its feet); ``main`` for an object."""
        return list(self._entity(entity).parts)

    def joints(self, entity: str) -> list[str]:
        """Movable joints of a robot or a person in URDF order; empty for objects."""
        return list(self._entity(entity).joints)

    # ------------------------------------------------------------------ grasping
    def attach(self, entity: str, part: str, obj: str) -> None:
        """A ``JOINT_FIXED`` constraint between ``part`` and ``obj`` at their current relative pose.

        Raises:
            BackendRefusal: ``part`` is not a gripper of ``entity`` or ``obj`` is not a graspable dynamic object.
        """
        self._wake()
        robot, target = self._entity(entity), self._entity(obj)
        key = (entity, part, obj)
        if key in self._grasps:
            return
        if key not in self._graspable:
            pairs = sorted(f"{p} + {o}" for (r, p, o) in self._graspable if r == entity)
            raise BackendRefusal(f"'{entity}' cannot attach '{obj}' to '{part}': only <gripper> parts hold "
                               f"graspable, non-static objects; possible: {', '.join(pairs) or 'none'}")
        self._grasps[key] = grasp.attach(self.client, robot, robot.link(part), target)
        self._pairs.hold_apart(self.client, robot, target)
        self._filters_changed = True

    def detach(self, entity: str, part: str, obj: str) -> None:
        """Remove the constraint (no effect if not attached)."""
        self._wake()
        cid = self._grasps.pop((entity, part, obj), None)
        if cid is not None:
            self._release(cid, self._entity(entity), self._entity(obj))

    def _release(self, cid: int, robot: EntityIndex, obj: EntityIndex) -> None:
        """Remove a grasp's constraint; the robot and the object collide again as their modes say."""
        grasp.detach(self.client, cid)
        self._pairs.release(self.client, robot, obj, self._bits)

    # ------------------------------------------------------------------ contacts and rays
    def contacts(self) -> frozenset[tuple[int, int]]:
        """Part-id pairs touching after the last step (``getContactPoints``, computed once per step)."""
        if self._contacts_tick != self._tick:
            self._contacts = self._contact_map.pairs(self.client)
            self._contacts_tick = self._tick
        return self._contacts

    def part_of(self, part_id: int) -> tuple[str, str]:
        """``(entity, part)`` of a part id; ``("ground", "main")`` for 0."""
        table = self._part_table
        if not 0 <= part_id < len(table):
            raise BackendRefusal(f"no part id {part_id}; valid ids: 0..{len(table) - 1}")
        return table[part_id]

    def ray_cast(self, origin: Array, directions: npt.NDArray[np.float64], max_range: float,
                 exclude: str | None = None) -> Array:
        """``rayTestBatch`` against collision shapes, passing through ``exclude``'s links (see :mod:`.rays`)."""
        c = self._client()
        if exclude is None:
            return rays.cast(c, origin, directions, max_range, None)
        e = self._entity(exclude)
        return rays.cast(c, origin, directions, max_range, e.body, e.links)

    def ray_hits(self, origin: Array, directions: npt.NDArray[np.float64], max_range: float,
                 among: Collection[str]) -> tuple[Array, list[str | None]]:
        """``rayTestBatch``, passing through every body but those of ``among`` (see :func:`.rays.first_hits`)."""
        c = self._client()
        bodies = {self._entity(name).body: name for name in among}
        distances, hit = rays.first_hits(c, origin, directions, max_range, bodies)
        return distances, [bodies.get(b) for b in hit.tolist()]
