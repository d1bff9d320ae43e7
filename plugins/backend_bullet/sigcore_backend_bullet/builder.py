"""A sigcore :class:`~sigcore.world.World` -> bodies in one PyBullet client.

* the ground: a ``GEOM_PLANE`` multibody at z = 0 (entity ``ground``), friction 1;
* an object: a multibody from ``createCollisionShape`` (box half extents = full lengths / 2; cylinder and
  capsule ``height`` = the world's length) or a mesh (``GEOM_MESH``, collides as its convex hull), or its URDF
  with ``loadURDF``; ``baseMass`` 0 / ``useFixedBase`` when ``static``;
* a human: its generated URDF (:mod:`sigcore.world.body`: REP-155 links, capsules, spheres and two foot boxes)
  with ``loadURDF`` as for a robot, root link ``main`` at the feet; held (static) with its revolute joints
  ``continuous``, dynamic with them ``fixed`` at their angles (a rigid mannequin: :func:`.urdf_prep.pose_joints`);
  no motors;
* a robot: ``loadURDF`` with ``URDF_USE_INERTIA_FROM_FILE`` (masses and inertias from ``<inertial>``) and
  ``URDF_USE_IMPLICIT_CYLINDER`` (round wheels, not a polygon hull); fixed links stay links; no
  self-collision (PyBullet's default without ``URDF_USE_SELF_COLLISION``).

No visual shapes are made: the client runs in ``DIRECT`` mode and sigcore renders nothing through it.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence

import pybullet as pb

from sigcore.backend import MAIN, entity_urdf
from sigcore.errors import BackendError
from sigcore.world.meshes import mesh_problem
from sigcore.world.models import Entity, Human, Object, Robot, World
from sigcore.world.urdf import UrdfDocument

from .frames import quat_from_rpy
from .layout import BASE, GROUP_STATIC, MASK_STATIC, EntityIndex, JointIndex
from .urdf_prep import pose_joints, prepare_urdf, write_temp

_URDF_FLAGS = pb.URDF_USE_INERTIA_FROM_FILE | pb.URDF_USE_IMPLICIT_CYLINDER
_DEFAULT_FRICTION = 1.0
"""Sliding friction of links without a friction tag (MuJoCo's default; PyBullet's own is 0.5)."""


def build_world(client: int, world: World) -> tuple[int, list[EntityIndex]]:
    """Create the ground and every entity of ``world`` in ``client``.

    Returns:
        The ground's body id, and one index per entity in world order.

    Raises:
        BackendError: a model file is missing or rejected; the message names the entity.
    """
    plane = pb.createCollisionShape(pb.GEOM_PLANE, physicsClientId=client)
    ground = pb.createMultiBody(0.0, plane, physicsClientId=client)
    pb.changeDynamics(ground, BASE, lateralFriction=1.0, physicsClientId=client)
    pb.setCollisionFilterGroupMask(ground, BASE, GROUP_STATIC, MASK_STATIC, physicsClientId=client)
    return ground, [build_entity(client, world, entity) for entity in world.entities]


def build_entity(client: int, world: World, entity: Entity) -> EntityIndex:
    """Create one entity of ``world`` in ``client`` (at build, or while running: nothing else is touched).

    Returns:
        Its index (body, links, parts, joints, masses at creation).

    Raises:
        BackendError: its model file is missing or rejected; the message names the entity. Nothing of it is left
            in the client.
    """
    if isinstance(entity, Robot):
        e = _add_robot(client, world, entity)
    elif isinstance(entity, Human):
        e = _add_human(client, world, entity)
    elif entity.urdf is not None:
        e = _add_urdf_object(client, world, entity)
    else:
        e = _add_shape_object(client, world, entity)
    try:
        _finish(client, e)
        if isinstance(entity, Object) and entity.urdf is not None and "mass" in entity.model_fields_set \
                and not entity.static:
            _scale_mass(client, e, entity.mass)
    except BackendError:
        pb.removeBody(e.body, physicsClientId=client)
        raise
    return e


def _finish(client: int, e: EntityIndex) -> None:
    """Record the base's inertial frame and the masses; set the collision filter of every link."""
    info = pb.getDynamicsInfo(e.body, BASE, physicsClientId=client)
    e.local_pos, e.local_orn = tuple(info[3]), tuple(info[4])
    known = len(e.masses0)  # a static primitive's mass is the world's (set by _add_shape_object)
    for i, link in enumerate(e.links):
        if i >= known:
            d = pb.getDynamicsInfo(e.body, link, physicsClientId=client)
            e.masses0.append(float(d[0]))
            e.inertia0.append(tuple(d[2]))
        pb.setCollisionFilterGroupMask(e.body, link, *e.filter_bits(link, True), physicsClientId=client)
        # PyBullet damps every body by default (0.04 linear, 0.04 angular): F = m a must hold exactly
        pb.changeDynamics(e.body, link, linearDamping=0.0, angularDamping=0.0, physicsClientId=client)


def _scale_mass(client: int, e: EntityIndex, mass: float) -> None:
    """Give a URDF object the world's total ``mass`` [kg]: every link's mass and inertia scaled alike."""
    total = sum(e.masses0)
    if total <= 0.0:
        raise BackendError(f"object '{e.name}' has no mass to scale (its URDF has no <inertial>)")
    factor = mass / total
    for i, link in enumerate(e.links):
        e.masses0[i] *= factor
        ix, iy, iz = e.inertia0[i]
        e.inertia0[i] = (ix * factor, iy * factor, iz * factor)
        if e.masses0[i] > 0.0:
            pb.changeDynamics(e.body, link, mass=e.masses0[i], localInertiaDiagonal=list(e.inertia0[i]),
                              physicsClientId=client)


def _load_urdf(client: int, urdf: UrdfDocument, what: str, pose_xyz: tuple[float, float, float],
               rpy: tuple[float, float, float], fixed: bool, scale: float = 1.0,
               rewrite: Callable[[str], str] | None = None) -> tuple[int, dict[str, float], frozenset[str]]:
    prepared = prepare_urdf(urdf, what, floating=not fixed)
    tmp = write_temp(prepared.text if rewrite is None else rewrite(prepared.text))
    try:
        body = pb.loadURDF(tmp, list(pose_xyz), quat_from_rpy(*rpy), useFixedBase=fixed, flags=_URDF_FLAGS,
                           globalScaling=scale, physicsClientId=client)
    except pb.error as err:
        raise BackendError(f"{what}: PyBullet cannot load URDF {urdf.path}: {err}") from None
    finally:
        os.unlink(tmp)
    return body, prepared.friction, prepared.massless


def _link_names(client: int, body: int) -> dict[str, int]:
    names = {pb.getBodyInfo(body, physicsClientId=client)[0].decode(): BASE}
    for j in range(pb.getNumJoints(body, physicsClientId=client)):
        names[pb.getJointInfo(body, j, physicsClientId=client)[12].decode()] = j
    return names


def _friction(client: int, body: int, links: dict[str, int], friction: dict[str, float],
              default: float) -> None:
    for name, link in links.items():
        mu = friction.get(name, default)
        pb.changeDynamics(body, link, lateralFriction=mu, physicsClientId=client)


# ---------------------------------------------------------------------------------------------------- robots
def _add_robot(client: int, world: World, robot: Robot) -> EntityIndex:
    what = f"robot '{robot.name}'"
    document = entity_urdf(world, robot.name, what)
    urdf = document.model
    body, friction, _ = _load_urdf(client, document, what, robot.pose.xyz, robot.pose.rpy, robot.fixed)
    links = _link_names(client, body)
    _friction(client, body, links, friction, _DEFAULT_FRICTION)
    n = pb.getNumJoints(body, physicsClientId=client)
    # every joint's default motor off: PyBullet starts each with a velocity motor of force 0.01 (wheels brake)
    pb.setJointMotorControlArray(body, list(range(n)), pb.VELOCITY_CONTROL, forces=[0.0] * n,
                                 physicsClientId=client)
    wheels = {robot.drive.left, robot.drive.right} if robot.drive is not None else set()
    joints: dict[str, JointIndex] = {}
    dt = world.timestep
    for j in urdf.movable_joints:
        index = links[j.child]
        if j.name in wheels and robot.drive is not None:
            joints[j.name] = JointIndex(index, True, robot.drive.max_torque)
        else:
            g = robot.gains
            effort = float(pb.getJointInfo(body, index, physicsClientId=client)[10])
            torque = min(g.max_torque, effort) if effort > 0 else g.max_torque
            gain = min(g.kp / g.kv, 1.0 / dt) if g.kv > 0 else 1.0 / dt  # [1/s]: target speed per error
            joints[j.name] = JointIndex(index, False, torque, gain, g.kp, g.kv)
    parts = [urdf.root] + [link for link in urdf.links if link != urdf.root]
    part_link = {part: links[part] for part in parts}
    part_link[MAIN] = BASE
    return EntityIndex(robot.name, "robot", body, parts, part_link, [BASE] + list(range(n)), robot.fixed, joints)


# -------------------------------------------------------------------------------------------- objects, humans
def _add_urdf_object(client: int, world: World, obj: Object) -> EntityIndex:
    assert obj.urdf is not None
    what = f"object '{obj.name}'"
    document = entity_urdf(world, obj.name, what, tree=False)
    body, friction, _ = _load_urdf(client, document, what, obj.pose.xyz, obj.pose.rpy, obj.static, obj.scale)
    links = _link_names(client, body)
    _friction(client, body, links, friction, obj.friction)
    n = pb.getNumJoints(body, physicsClientId=client)
    if n:
        pb.setJointMotorControlArray(body, list(range(n)), pb.VELOCITY_CONTROL, forces=[0.0] * n,
                                     physicsClientId=client)
    return EntityIndex(obj.name, "object", body, [MAIN], {MAIN: BASE}, [BASE] + list(range(n)), obj.static)


def _add_shape_object(client: int, world: World, obj: Object) -> EntityIndex:
    if obj.mesh is not None:
        path = world.resolve(obj.mesh)
        if not path.is_file():
            raise BackendError(f"object '{obj.name}': mesh file {path} not found")
        problem = mesh_problem(path)  # PyBullet crashes the process on some broken meshes: never hand it one
        if problem is not None:
            raise BackendError(f"object '{obj.name}': mesh {path}: {problem}")
        try:
            shape = pb.createCollisionShape(pb.GEOM_MESH, fileName=str(path.resolve()), meshScale=[obj.scale] * 3,
                                            physicsClientId=client)
        except pb.error as err:
            raise BackendError(f"object '{obj.name}': PyBullet cannot read mesh {path}: {err} "
                               "(PyBullet reads .obj and .stl meshes)") from None
    else:
        assert obj.shape is not None and obj.size is not None
        shape = _primitive(client, obj.shape, obj.size)
    body = pb.createMultiBody(0.0 if obj.static else obj.mass, shape, basePosition=list(obj.pose.xyz),
                              baseOrientation=quat_from_rpy(*obj.pose.rpy), physicsClientId=client)
    pb.changeDynamics(body, BASE, lateralFriction=obj.friction, physicsClientId=client)
    e = EntityIndex(obj.name, "object", body, [MAIN], {MAIN: BASE}, [BASE], obj.static)
    if obj.static:  # report the world's mass, as the MuJoCo backend does, though PyBullet holds it with mass 0
        e.masses0.append(obj.mass)
        info = pb.getDynamicsInfo(body, BASE, physicsClientId=client)
        e.inertia0.append(tuple(info[2]))
    return e


def _primitive(client: int, shape: str, size: tuple[float, ...]) -> int:
    """A collision shape from a world primitive (box full lengths -> half extents; lengths are full lengths)."""
    if shape == "box":
        return int(pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[s / 2 for s in size], physicsClientId=client))
    if shape == "sphere":
        return int(pb.createCollisionShape(pb.GEOM_SPHERE, radius=size[0], physicsClientId=client))
    kind = pb.GEOM_CYLINDER if shape == "cylinder" else pb.GEOM_CAPSULE
    return int(pb.createCollisionShape(kind, radius=size[0], height=size[1], physicsClientId=client))


def _add_human(client: int, world: World, human: Human, angles: Sequence[float] | None = None,
               rigid: bool | None = None) -> EntityIndex:
    """A person from its generated URDF (``world.urdf``), at its model pose.

    Args:
        angles: Its joint angles [rad] in URDF order (default: all 0, as the URDF has them).
        rigid: Build it as a rigid mannequin (joints fixed at ``angles``) rather than with kinematic joints
            (default: rigid when it is not static).
    """
    what = f"human '{human.name}'"
    document = entity_urdf(world, human.name, what)
    urdf = document.model
    movable = urdf.movable_joints
    posture = [0.0] * len(movable) if angles is None else [float(a) for a in angles]
    rigid = not human.static if rigid is None else rigid
    by_name = {j.name: q for j, q in zip(movable, posture, strict=True)}
    body, friction, _ = _load_urdf(client, document, what, human.pose.xyz, human.pose.rpy, False,
                                   rewrite=lambda text: pose_joints(text, by_name if rigid else None))
    links = _link_names(client, body)
    _friction(client, body, links, friction, _DEFAULT_FRICTION)
    n = pb.getNumJoints(body, physicsClientId=client)
    # every joint's default motor off (PyBullet starts each with a velocity motor that brakes it)
    pb.setJointMotorControlArray(body, list(range(n)), pb.VELOCITY_CONTROL, forces=[0.0] * n,
                                 physicsClientId=client)
    joints = {j.name: JointIndex(links[j.child], False, 0.0) for j in movable}
    if not rigid and any(posture):
        indices = [j.index for j in joints.values()]
        pb.resetJointStatesMultiDof(body, indices, [[q] for q in posture], [[0.0]] * len(indices),
                                    physicsClientId=client)
    parts = [urdf.root] + [link for link in urdf.links if link != urdf.root]
    part_link = {part: links[part] for part in parts}
    part_link[MAIN] = BASE
    return EntityIndex(human.name, "human", body, parts, part_link, [BASE] + list(range(n)), False, joints,
                       held0=human.static, rigid=rigid)


def rebuild_human(client: int, world: World, e: EntityIndex, angles: Sequence[float], rigid: bool) -> EntityIndex:
    """Replace the body of the person ``e`` by a new one (rigid, or with kinematic joints) with these joint
    ``angles``, its base where and as fast as ``e``'s (the old body is removed).

    Returns:
        The new index (same parts, joints and link indices; its masses those of the URDF, its collision filters
        the default ones: the caller applies its own).
    """
    human = world.agent(e.name)
    assert isinstance(human, Human)
    pos, orn = pb.getBasePositionAndOrientation(e.body, physicsClientId=client)
    lin, ang = pb.getBaseVelocity(e.body, physicsClientId=client)
    new = _add_human(client, world, human, angles, rigid)  # made before the old one goes: a failure leaves it
    _finish(client, new)
    pb.removeBody(e.body, physicsClientId=client)
    pb.resetBasePositionAndOrientation(new.body, pos, orn, physicsClientId=client)
    pb.resetBaseVelocity(new.body, lin, ang, physicsClientId=client)
    return new
