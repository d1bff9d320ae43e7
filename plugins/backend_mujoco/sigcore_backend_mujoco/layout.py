"""Index arrays of the compiled model, computed once at build so that per-step work is numpy slicing.

Every MuJoCo body belongs to one entity (its name is ``<entity>/...``) or to the world (the ground). Part ids,
used by contacts, are: 0 for the ground, then one per entity part (a robot's or a person's link; the single
``main`` of an object, which every body of a URDF object maps to).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np
import numpy.typing as npt

from sigcore.backend import GROUND, MAIN, find_joint, find_part

from .plan import EntityPlan, WeldPlan, lock_name, prefix
from .servo import POSITION, ArmServo, Drive, WheelMotor, motor_name

Ints = npt.NDArray[np.int64]

_QPOS_SIZE = {int(mujoco.mjtJoint.mjJNT_FREE): 7, int(mujoco.mjtJoint.mjJNT_BALL): 4}
_DOF_SIZE = {int(mujoco.mjtJoint.mjJNT_FREE): 6, int(mujoco.mjtJoint.mjJNT_BALL): 3}


@dataclass
class JointIndex:
    """One actuated joint.

    Attributes:
        jnt: Joint id.
        qpos: Its qpos address.
        dof: Its dof (qvel) address.
        servo: Its drive: an arm servo or a wheel motor; None for a person's joint (no actuator, held).
        lock: A person's joint: the equality that holds its angle while the person is dynamic; -1 otherwise.
    """

    jnt: int
    qpos: int
    dof: int
    servo: Drive | None
    lock: int = -1


@dataclass
class EntityIndex:
    """Where an entity lives in the model.

    Attributes:
        name: Entity name.
        kind: ``robot``, ``object`` or ``human``.
        parts: Part names, main part first.
        part_body: Body id of each part (``"main"`` too, for robots: the root link).
        root: Body id of the main part.
        bodies: (B,) body ids of all the entity's bodies.
        geoms: (G,) geom ids of all the entity's geoms.
        free_qpos: qpos address of its free joint, -1 if welded to the world.
        free_dof: dof address of its free joint, -1 if welded.
        qpos: (Q,) qpos addresses of all its joints.
        dofs: (D,) dof addresses of all its joints.
        joints: Movable joints by URDF name, in URDF order (a robot's actuated ones, a person's passive ones).
        held0: Dynamics off at build (static humans).
    """

    name: str
    kind: str
    parts: list[str]
    part_body: dict[str, int]
    root: int
    bodies: Ints
    geoms: Ints
    free_qpos: int
    free_dof: int
    qpos: Ints
    dofs: Ints
    joints: dict[str, JointIndex] = field(default_factory=dict)
    held0: bool = False

    @property
    def welded(self) -> bool:
        """Root welded to the world (a static object or a fixed robot)."""
        return self.free_qpos < 0

    def body(self, part: str | None) -> int:
        """Body id of ``part`` (``None`` or ``"main"``: the main part).

        Raises:
            BackendRefusal: no such part; the message lists the valid ones.
        """
        return self.root if part is None else find_part(self.kind, self.name, self.part_body, part, self.parts)

    def joint(self, name: str) -> JointIndex:
        """The actuated joint ``name``; :class:`BackendRefusal` listing the valid joints otherwise."""
        return find_joint(self.kind, self.name, self.joints, name)


@dataclass
class Layout:
    """All index arrays of the model.

    Attributes:
        entities: By name, in world order.
        part_table: ``(entity, part)`` of each part id; id 0 is ``(GROUND, MAIN)``.
        geom_part: (ngeom,) part id of each geom.
        part_entity: (nparts,) entity number of each part id (-1 for the ground).
        welds: Weld equality id of each ``(robot, gripper part, object)``.
    """

    entities: dict[str, EntityIndex]
    part_table: list[tuple[str, str]]
    geom_part: Ints
    part_entity: Ints
    welds: dict[tuple[str, str, str], int]


def index_model(model: mujoco.MjModel, plans: list[EntityPlan], welds: list[WeldPlan]) -> Layout:
    """Compute the index arrays of a compiled model built from ``plans``."""
    body_entity = [str(model.body(b).name).split("/", 1)[0] if b else "" for b in range(model.nbody)]
    part_table: list[tuple[str, str]] = [(GROUND, MAIN)]
    part_entity = [-1]
    body_part = np.zeros(model.nbody, dtype=np.int64)
    entities: dict[str, EntityIndex] = {}
    for number, plan in enumerate(plans):
        bodies = np.array([b for b in range(model.nbody) if body_entity[b] == plan.name], dtype=np.int64)
        part_body = {part: model.body(body).id for part, body in plan.parts}
        main_id = len(part_table)
        for part, _ in plan.parts:
            body_part[part_body[part]] = len(part_table)
            part_table.append((plan.name, part))
            part_entity.append(number)
        if plan.kind == "object":
            body_part[bodies] = main_id  # every body of a (URDF) object is its main part
        root = part_body[plan.parts[0][0]]
        if plan.kind != "object":
            part_body[MAIN] = root
        entities[plan.name] = _entity(model, plan, bodies, part_body, root)
    geom_part = body_part[model.geom_bodyid]
    weld_ids = {(w.robot, w.part, w.obj): model.equality(w.name).id for w in welds}
    return Layout(entities, part_table, geom_part, np.array(part_entity, dtype=np.int64), weld_ids)


def _entity(model: mujoco.MjModel, plan: EntityPlan, bodies: Ints, part_body: dict[str, int],
            root: int) -> EntityIndex:
    in_entity = np.isin(model.jnt_bodyid, bodies)
    qpos: list[int] = []
    dofs: list[int] = []
    free_qpos = free_dof = -1
    for j in np.flatnonzero(in_entity):
        jtype = int(model.jnt_type[j])
        qa, da = int(model.jnt_qposadr[j]), int(model.jnt_dofadr[j])
        qpos += range(qa, qa + _QPOS_SIZE.get(jtype, 1))
        dofs += range(da, da + _DOF_SIZE.get(jtype, 1))
        if jtype == mujoco.mjtJoint.mjJNT_FREE and int(model.jnt_bodyid[j]) == root:
            free_qpos, free_dof = qa, da
    joints: dict[str, JointIndex] = {}
    for jp in plan.joints:
        name = prefix(plan.name) + jp.name
        jnt = model.joint(name).id
        qa, da = int(model.jnt_qposadr[jnt]), int(model.jnt_dofadr[jnt])
        servo: Drive | None
        lock = -1
        if jp.passive:
            servo, lock = None, model.equality(lock_name(plan.name, jp.name)).id
        elif jp.wheel:
            motor = motor_name(plan.name, jp.name)
            servo = WheelMotor(int(model.jnt_dofadr[model.joint(motor).id]), model.tendon(motor).id,
                               jp.max_torque, jp.max_torque)
        else:
            act = model.actuator(name).id
            servo = ArmServo(act, int(model.actuator_actadr[act]), qa, jp.max_torque, POSITION, jp.max_torque)
        joints[jp.name] = JointIndex(jnt, qa, da, servo, lock)
    geoms = np.flatnonzero(np.isin(model.geom_bodyid, bodies)).astype(np.int64)
    return EntityIndex(plan.name, plan.kind, [p for p, _ in plan.parts], part_body, root, bodies, geoms,
                       free_qpos, free_dof, np.array(qpos, dtype=np.int64), np.array(dofs, dtype=np.int64),
                       joints, plan.held)
