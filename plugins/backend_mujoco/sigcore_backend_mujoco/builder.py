"""A sigcore :class:`~sigcore.world.World` -> a MuJoCo spec (``mujoco.MjSpec``) and a plan per entity.

Layout of the spec:

* the ground: a plane at z = 0 in the world body (entity ``ground``), and a directional light;
* an object: body ``<name>/main`` at its pose (a primitive or mesh geom), or its URDF attached at its pose; a
  free joint unless ``static`` (then the body is welded to the world);
* a human: its generated URDF (:mod:`sigcore.world.body`: REP-155 links, capsules, spheres and feet boxes) attached
  at its pose with prefix ``<name>/``, root body ``<name>/main`` at the feet, a free joint; no actuators (its
  joints are held where ``set_joint_angle`` puts them, see :mod:`.backend`), and per joint a joint equality
  ``lock:<name>:<joint>`` that holds the angle while the person is dynamic (a mannequin); no self-collision;
* a robot: its URDF attached at its pose with prefix ``<name>/`` (bodies keep the URDF link names), a free
  joint on the root link unless ``fixed``; an integrator servo per arm joint, and per drive wheel a hidden
  motor body ``motor:<robot>:<joint>`` with a friction tendon (see :mod:`.servo`); no self-collision (every
  pair of its bodies is excluded, as Gazebo and PyBullet do by default);
* one disabled weld per (gripper part, graspable dynamic object), switched on by a grasp (see :mod:`.grasp`).

Options: the ``implicitfast`` integrator (servo damping integrated implicitly), elliptic friction cones and
``noslip`` iterations (without them a robot resting on braked wheels and two casters rocked and crept 4 cm in
2 s on the clean-up world); a sparse Jacobian at any size, so that adding or removing entities while running
leaves the others' trajectories bit for bit (see :mod:`.carry`; about 1 % slower per step than MuJoCo's dense
choice on the 50 dofs of the clean-up world, 10 % on the 6 of ``arm6``).

:func:`add_to_spec` adds entities to an existing spec the same way (a new entity's elements after all others);
:func:`rebuild_spec` lays out a world without some entities with the elements of the others in the same order
(deleting elements from a spec one by one cost 0.2 ms each, 0.15 s for a robot and its 300 excluded body pairs).
"""

from __future__ import annotations

from collections.abc import Sequence
from itertools import combinations

import mujoco
import numpy as np

from sigcore.backend import entity_urdf
from sigcore.errors import BackendError
from sigcore.geometry import quat_from_rpy
from sigcore.world.appearance import Color, link_colors
from sigcore.world.models import Human, Object, Pose, Robot, World
from sigcore.world.visuals import DEFAULT_COLOR

from .plan import (
    FREE_JOINT,
    GROUND,
    GROUP_COLLISION,
    GROUP_VISUAL,
    NORMAL,
    EntityPlan,
    JointPlan,
    WeldPlan,
    lock_name,
    prefix,
)
from .servo import MOTOR_ARMATURE, motor_name
from .urdf_spec import load_urdf

_GEOM = mujoco.mjtGeom
ENTITY_PRIORITY = 1
"""Contact priority of entity geoms over the ground (0): a contact with the ground takes the entity's
friction. Between two entities MuJoCo takes the larger of the two frictions."""

_MIN_ALPHA = 0.001
_NOSLIP_ITERATIONS = 5
"""Friction post-processing: without it, the soft friction constraints of wheel motors and contacts creep."""
_MOTOR_SOLREF = (0.004, 1.0)
_MOTOR_SOLIMP = (0.99, 0.999, 0.001, 0.5, 2.0)
_WELD_SOLREF = (0.01, 1.0)
_WELD_SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)


def build_spec(world: World) -> tuple[mujoco.MjSpec, list[EntityPlan], list[WeldPlan]]:
    """Lay out ``world`` in a new spec.

    Returns:
        The spec (not compiled), one plan per entity in world order, and the grasp welds.

    Raises:
        BackendError: a model file is missing or rejected; the message names the entity.
    """
    spec = _new_spec(world)
    plans, welds = add_to_spec(spec, world, [e.name for e in world.entities], [])
    return spec, plans, welds


def add_to_spec(spec: mujoco.MjSpec, world: World, names: Sequence[str],
                plans: Sequence[EntityPlan]) -> tuple[list[EntityPlan], list[WeldPlan]]:
    """Lay out the entities ``names`` of ``world`` in ``spec``, which holds those of ``plans`` already.

    Every element of a new entity is added after the existing ones (bodies, joints, actuators, tendons, welds),
    so the compiled model keeps the ids and dof order of the existing ones. The grasp welds added are those that
    involve a new entity: its grippers x every graspable object, every gripper x it if graspable.

    Returns:
        The new entities' plans in world order, and the new grasp welds.

    Raises:
        BackendError: a model file is missing or rejected; the message names the entity. ``spec`` may then hold
            part of the new entities: callers work on a copy.
    """
    new = set(names)
    added = [_add_entity(spec, world, e) for e in world.entities if e.name in new]
    welds = _add_welds(spec, world, {p.name: p for p in [*plans, *added]}, new)
    return added, welds


def rebuild_spec(world: World, welds: Sequence[WeldPlan]) -> tuple[mujoco.MjSpec, list[EntityPlan]]:
    """Lay out ``world`` in a new spec with the grasp welds ``welds``, in that order (removing entities while
    running: the running spec without them, every remaining element in the same order, nothing left behind).

    Raises:
        BackendError: a model file is missing or rejected; the message names the entity.
    """
    spec = _new_spec(world)
    plans = [_add_entity(spec, world, e) for e in world.entities]
    by_name = {p.name: p for p in plans}
    for weld in welds:
        _add_weld(spec, weld, by_name)
    return spec, plans


def _add_entity(spec: mujoco.MjSpec, world: World, entity: Robot | Object | Human) -> EntityPlan:
    if isinstance(entity, Robot):
        return _add_robot(spec, world, entity)
    if isinstance(entity, Human):
        return _add_human(spec, world, entity)
    if entity.urdf is not None:
        return _add_urdf_object(spec, world, entity)
    return _add_shape_object(spec, world, entity)


def _new_spec(world: World) -> mujoco.MjSpec:
    """An empty spec with the world's options, the ground and a light."""
    spec = mujoco.MjSpec()
    spec.modelname = world.name
    spec.option.timestep = world.timestep
    spec.option.gravity = list(world.gravity)
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.noslip_iterations = _NOSLIP_ITERATIONS
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.jacobian = mujoco.mjtJacobian.mjJAC_SPARSE  # bit-for-bit runs when entities come and go (.carry)
    spec.compiler.fusestatic = False
    _add_ground(spec)
    return spec


# ------------------------------------------------------------------------------------------- ground and poses
def _add_ground(spec: mujoco.MjSpec) -> None:
    spec.worldbody.add_geom(name="ground", type=_GEOM.mjGEOM_PLANE, size=[0.0, 0.0, 1.0],
                            rgba=[0.8, 0.8, 0.8, 1.0], group=GROUP_COLLISION,
                            contype=GROUND[0], conaffinity=GROUND[1])
    spec.worldbody.add_light(name="sun", pos=[0.0, 0.0, 10.0], dir=[0.3, 0.2, -1.0],
                             type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)


def _frame(pose: Pose) -> tuple[list[float], list[float]]:
    return list(pose.xyz), quat_from_rpy(*pose.rpy).tolist()


def _style(body: mujoco.MjsBody, friction: dict[str, float], default: float | None,
           colors: dict[str, Color]) -> None:
    """Give every geom below ``body`` the backend's collision bits, group and friction (per body name), and the
    colour of its link in the scene description (:func:`sigcore.world.appearance.link_colors`: what the camera shows
    is what the viewer shows)."""
    for geom in body.find_all(mujoco.mjtObj.mjOBJ_GEOM):
        if geom.contype == 0 and geom.conaffinity == 0:
            geom.group = GROUP_VISUAL
            continue
        geom.group = GROUP_COLLISION
        geom.contype, geom.conaffinity = NORMAL
        geom.priority = ENTITY_PRIORITY
        link = str(geom.parent.name).split("/", 1)[-1]
        mu = friction.get(link, default)
        if mu is not None:
            geom.friction[0] = mu
            if mu == 0.0:
                geom.condim = 1  # frictionless: a zero-width friction pyramid is degenerate for the solver
        geom.rgba = _visible(colors.get(link, DEFAULT_COLOR))


def _visible(rgba: tuple[float, ...]) -> list[float]:
    """``rgba`` with alpha at least 0.001: MuJoCo's rays skip fully transparent geoms, lidars must not."""
    return [rgba[0], rgba[1], rgba[2], max(rgba[3], _MIN_ALPHA)]


def _exclude_self(spec: mujoco.MjSpec, root: mujoco.MjsBody) -> None:
    bodies = [root.name, *(b.name for b in root.find_all(mujoco.mjtObj.mjOBJ_BODY))]
    for a, b in combinations(bodies, 2):
        spec.add_exclude(bodyname1=a, bodyname2=b)


# ---------------------------------------------------------------------------------------------------- robots
def _add_robot(spec: mujoco.MjSpec, world: World, robot: Robot) -> EntityPlan:
    what = f"robot '{robot.name}'"
    document = entity_urdf(world, robot.name, what)
    urdf = document.model
    loaded = load_urdf(document, what)
    root = _attach(spec, loaded.spec, robot.name, robot.pose, free=not robot.fixed)
    _style(root, loaded.friction, None, link_colors(world, robot))
    _exclude_self(spec, root)
    wheels = {robot.drive.left, robot.drive.right} if robot.drive is not None else set()
    joints: list[JointPlan] = []
    for j in urdf.movable_joints:
        limits = None
        if j.lower is not None and j.upper is not None and j.lower < j.upper:
            limits = (j.lower, j.upper)
        if j.name in wheels and robot.drive is not None:
            plan = JointPlan(j.name, True, 0.0, 0.0, robot.drive.max_torque)
        else:
            plan = JointPlan(j.name, False, robot.gains.kp, robot.gains.kv, robot.gains.max_torque, limits)
        if plan.wheel:
            _add_motor(spec, robot.name, plan)
        else:
            _add_actuator(spec, robot.name, plan)
        joints.append(plan)
    p = prefix(robot.name)
    parts = [(urdf.root, p + urdf.root)] + [(link, p + link) for link in urdf.links if link != urdf.root]
    return EntityPlan(robot.name, "robot", parts, free=not robot.fixed, joints=joints)


def _attach(spec: mujoco.MjSpec, child: mujoco.MjSpec, name: str, pose: Pose, free: bool) -> mujoco.MjsBody:
    pos, quat = _frame(pose)
    frame = spec.worldbody.add_frame(pos=pos, quat=quat)
    root = frame.attach_body(child.worldbody.first_body(), prefix(name), "")
    if free:
        root.add_freejoint(name=prefix(name) + FREE_JOINT)
    return root


def _add_actuator(spec: mujoco.MjSpec, robot: str, joint: JointPlan) -> None:
    """An arm joint's integrator servo, ``force = kp * act - kp * q - kv * qdot`` (see :mod:`.servo`)."""
    name = prefix(robot) + joint.name
    act = spec.add_actuator(name=name, target=name)
    act.trntype = mujoco.mjtTrn.mjTRN_JOINT
    act.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
    act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
    act.biastype = mujoco.mjtBias.mjBIAS_AFFINE
    act.gainprm[0] = joint.kp
    act.biasprm[0:3] = [0.0, -joint.kp, -joint.kv]
    act.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
    act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
    act.forcerange = [-joint.max_torque, joint.max_torque]
    if joint.limits is not None:
        act.actlimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.actrange = list(joint.limits)
    else:
        act.actlimited = mujoco.mjtLimited.mjLIMITED_FALSE


def _add_motor(spec: mujoco.MjSpec, robot: str, joint: JointPlan) -> None:
    """A drive wheel's velocity motor: a hidden spinning joint and a friction tendon (see :mod:`.servo`)."""
    name = motor_name(robot, joint.name)
    body = spec.worldbody.add_body(name=name, mass=1.0, inertia=[1.0, 1.0, 1.0])
    body.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 0.0, 1.0], armature=MOTOR_ARMATURE)
    tendon = spec.add_tendon(name=name, frictionloss=joint.max_torque, solref_friction=list(_MOTOR_SOLREF),
                             solimp_friction=list(_MOTOR_SOLIMP))
    tendon.wrap_joint(prefix(robot) + joint.name, 1.0)
    tendon.wrap_joint(name, -1.0)


# -------------------------------------------------------------------------------------------- objects, humans
def _add_urdf_object(spec: mujoco.MjSpec, world: World, obj: Object) -> EntityPlan:
    assert obj.urdf is not None
    what = f"object '{obj.name}'"
    loaded = load_urdf(entity_urdf(world, obj.name, what, tree=False), what, obj.scale)
    root = _attach(spec, loaded.spec, obj.name, obj.pose, free=not obj.static)
    _style(root, loaded.friction, obj.friction, link_colors(world, obj))
    _exclude_self(spec, root)
    mass = obj.mass if "mass" in obj.model_fields_set and not obj.static else None
    return EntityPlan(obj.name, "object", [("main", str(root.name))], free=not obj.static, total_mass=mass)


def _add_shape_object(spec: mujoco.MjSpec, world: World, obj: Object) -> EntityPlan:
    pos, quat = _frame(obj.pose)
    name = prefix(obj.name) + "main"
    body = spec.worldbody.add_body(name=name, pos=pos, quat=quat)
    if not obj.static:
        body.add_freejoint(name=prefix(obj.name) + FREE_JOINT)
    geom = body.add_geom(name=name, mass=obj.mass, rgba=_visible(obj.color), group=GROUP_COLLISION,
                         contype=NORMAL[0], conaffinity=NORMAL[1], priority=ENTITY_PRIORITY)
    geom.friction[0] = obj.friction
    if obj.friction == 0.0:
        geom.condim = 1
    if obj.mesh is not None:
        path = world.resolve(obj.mesh)
        if not path.is_file():
            raise BackendError(f"object '{obj.name}': mesh file {path} not found")
        mesh = spec.add_mesh(name=prefix(obj.name) + "mesh", file=str(path.resolve()))
        mesh.scale = [obj.scale] * 3
        geom.type = _GEOM.mjGEOM_MESH
        geom.meshname = mesh.name
    else:
        assert obj.shape is not None and obj.size is not None
        geom.type, geom.size = _primitive(obj.shape, obj.size)
    return EntityPlan(obj.name, "object", [("main", name)], free=not obj.static)


def _primitive(shape: str, size: tuple[float, ...]) -> tuple[mujoco.mjtGeom, list[float]]:
    """MuJoCo type and size of a world primitive (box full lengths -> half sizes; lengths -> half lengths)."""
    if shape == "box":
        return _GEOM.mjGEOM_BOX, [s / 2 for s in size]
    if shape == "sphere":
        return _GEOM.mjGEOM_SPHERE, [size[0], 0.0, 0.0]
    if shape == "cylinder":
        return _GEOM.mjGEOM_CYLINDER, [size[0], size[1] / 2, 0.0]
    return _GEOM.mjGEOM_CAPSULE, [size[0], size[1] / 2, 0.0]


def _add_human(spec: mujoco.MjSpec, world: World, human: Human) -> EntityPlan:
    what = f"human '{human.name}'"
    document = entity_urdf(world, human.name, what)
    loaded = load_urdf(document, what)
    root = _attach(spec, loaded.spec, human.name, human.pose, free=True)
    _style(root, loaded.friction, 1.0, link_colors(world, human))
    _exclude_self(spec, root)
    urdf = document.model
    joints = [JointPlan(j.name, False, 0.0, 0.0, 0.0, (j.lower, j.upper) if j.lower is not None and
                        j.upper is not None else None, passive=True) for j in urdf.movable_joints]
    p = prefix(human.name)
    for j in joints:  # a dynamic person's joints are locked by these (a mannequin); a held one needs none
        spec.add_equality(name=lock_name(human.name, j.name), type=mujoco.mjtEq.mjEQ_JOINT,
                          objtype=mujoco.mjtObj.mjOBJ_JOINT, name1=p + j.name, active=not human.static,
                          data=[0.0] * mujoco.mjNEQDATA)
    parts = [(urdf.root, p + urdf.root)] + [(link, p + link) for link in urdf.links if link != urdf.root]
    return EntityPlan(human.name, "human", parts, free=True, held=human.static, joints=joints)


# ----------------------------------------------------------------------------------------------- grasp welds
def _add_welds(spec: mujoco.MjSpec, world: World, by_name: dict[str, EntityPlan], new: set[str]) -> list[WeldPlan]:
    """One disabled weld per (gripper part, graspable dynamic object) pair with a robot or object in ``new``."""
    targets = [o for o in world.entities if isinstance(o, Object) and o.graspable and not o.static]
    welds: list[WeldPlan] = []
    for robot in (r for r in world.entities if isinstance(r, Robot)):
        for gripper in robot.grippers:
            for obj in targets:
                if robot.name in new or obj.name in new:
                    name = f"grasp:{robot.name}/{gripper.part}:{obj.name}"
                    welds.append(_add_weld(spec, WeldPlan(robot.name, gripper.part, obj.name, name), by_name))
    return welds


def _add_weld(spec: mujoco.MjSpec, weld: WeldPlan, by_name: dict[str, EntityPlan]) -> WeldPlan:
    data = np.zeros(mujoco.mjNEQDATA)
    data[6] = 1.0  # relpose quaternion: given (not recomputed at qpos0 by mj_setConst)
    data[10] = 1.0  # torquescale
    spec.add_equality(name=weld.name, type=mujoco.mjtEq.mjEQ_WELD, objtype=mujoco.mjtObj.mjOBJ_BODY,
                      name1=prefix(weld.robot) + weld.part, name2=by_name[weld.obj].parts[0][1], active=False,
                      data=data.tolist(), solref=list(_WELD_SOLREF), solimp=list(_WELD_SOLIMP))
    return weld
